#include "coupling/particle_plastic_heat.h"

#include "coupling/host_cell_source.h"

#include <algorithm>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
std::vector<double> ParticlePlasticHeat<dim>::current_work() const {
  const auto& particles = state_.particles;
  std::vector<double> w(particles.size(), 0.0);
  if (!state_.method || !state_.method->has_plastic_work())
    return w;
  const auto d = state_.method->plastic_work_density(particles);
  for (unsigned int i = 0; i < w.size() && i < d.size(); ++i)
    w[i] = d[i] * particles.volume(i);
  return w;
}

template <int dim>
void ParticlePlasticHeat<dim>::track_new_particles() {
  if (state_.heat && state_.method && state_.method->has_plastic_work())
    take_baselines(current_work());
}

template <int dim>
void ParticlePlasticHeat<dim>::take_baselines(const std::vector<double>& w) {
  // Particles are only ever appended (CouplingState::add_particle), so an index keeps its
  // particle; new indices, and ghosts a conversion made free, start from what they inherited
  // (the cell's work, which heated the FEM); a ghost's follows the FEM.
  for (unsigned int i = 0; i < w.size(); ++i) {
    const bool is_free = state_.free[i];
    if (i >= booked_.size()) {
      booked_.push_back(w[i]);
      free_.push_back(is_free);
    } else if (!is_free || !free_[i]) {
      booked_[i] = w[i];
      free_[i] = is_free;
    }
  }
}

template <int dim>
Vector<double> ParticlePlasticHeat<dim>::take(double beta, double elapsed) {
  Vector<double> power(state_.fem.dof_handler().get_triangulation().n_active_cells());
  if (!state_.method || !state_.method->has_plastic_work() || !(elapsed > 0))
    return power;
  const auto w = current_work();
  take_baselines(w);
  // Each particle's increment since its baseline; the baselines move on for every particle
  // on every rank (all ranks hold all particles), whichever rank hands the heat over.
  // Plastic dissipation is never negative: a particle's work can fall only where its history
  // lost weight (NOSB-PD families rebuilt after breaks, a failed family), which gives no heat
  // back; the baseline follows it down.
  std::vector<double> increment(w.size(), 0.0);
  for (unsigned int i = 0; i < w.size(); ++i) {
    if (state_.free[i])
      increment[i] = std::max(0.0, w[i] - booked_[i]);
    booked_[i] = w[i];
  }
  const double work = host_cell_power(state_, increment, beta, elapsed, power);
  work_ += work;
  heat_ += beta * work;
  return power;
}

template <int dim>
void ParticlePlasticHeat<dim>::restore(double heat, double work) {
  heat_ = heat;
  work_ = work;
  booked_.clear();
  free_.clear();
  track_new_particles();
}

template class ParticlePlasticHeat<2>;
template class ParticlePlasticHeat<3>;

} // namespace spinesim::coupling
