#include "coupling/particle_energy.h"

#include <chrono>

namespace spinesim::coupling {

namespace {
// The back halves of a step's sums were formed with dt; the previous step had dt_back.
inline void scale_back(fem::ExplicitEnergy::Step& step, double ratio) {
  step.external_back *= ratio;
  step.prescribed_back *= ratio;
  step.damping_back *= ratio;
}
} // namespace

template <int dim>
double ParticleEnergy<dim>::stored_energy() const {
  if (!state_.method || state_.n_free_particles() == 0)
    return 0;
  const auto start = std::chrono::steady_clock::now();
  double e = 0; // rows of ghosts and of other ranks' particles are not this rank's
  if (splice_stored_) {
    e = splice_stored_();
  } else {
    // Stored energy plus the plastic work the particles' history holds: the FEM's internal
    // work holds both, and so the account's U is the internal work on both sides.
    const auto w = state_.method->strain_energy_density(state_.particles, state_.bonds);
    for (unsigned int i = 0; i < w.size(); ++i)
      if (state_.free[i] && state_.is_owned(i))
        e += w[i] * state_.particles.volume(i);
    const auto d = state_.method->plastic_work_density(state_.particles);
    for (unsigned int i = 0; i < d.size(); ++i)
      if (state_.free[i] && state_.is_owned(i))
        e += d[i] * state_.particles.volume(i);
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return e;
}

template <int dim>
std::vector<double> ParticleEnergy<dim>::saved_sums() const {
  auto sums = account_.works();
  sums.push_back(fracture_);
  return sums;
}

template <int dim>
void ParticleEnergy<dim>::restore_sums(const std::vector<double>& sums) {
  account_.set_works(sums);
  if (sums.size() > fem::ExplicitEnergy::n_works)
    fracture_ = sums[fem::ExplicitEnergy::n_works];
}

template <int dim>
void ParticleEnergy<dim>::before_forces() {
  if (!on_)
    return;
  stored_before_ = stored_energy();
  if (splice_rows_)
    rows_before_ = splice_rows_();
  broken_before_ = state_.bonds.broken;
  velocity_before_ = state_.particles.velocities();
  std::swap(u_last_, u_now_);
  u_now_ = state_.particles.displacements();
  forces_before_.clear();
  reactions_before_.clear();
}

template <int dim>
void ParticleEnergy<dim>::record_forces_before_breaks() {
  if (!on_)
    return;
  forces_before_ = state_.particles.forces();
  if (splice_stored_)
    reactions_before_ = *state_.method->driven_reactions(state_.particles, state_.bonds);
}

template <int dim>
void ParticleEnergy<dim>::after_forces() {
  if (!on_)
    return;
  stored_ = stored_before_;
  if (state_.bonds.broken != broken_before_) { // the same displacements, fewer bonds
    // Only this rank's rows changed (with the splice the rest of its energy is collective).
    stored_ = splice_rows_ ? stored_before_ - rows_before_ + splice_rows_() : stored_energy();
    double lost_work = 0;
    const auto& p = state_.particles;
    if (forces_before_.size() == p.size() && u_last_.size() == p.size()) {
      std::vector<dealii::Tensor<1, dim>> reactions;
      if (reactions_before_.size() == p.size())
        reactions = *state_.method->driven_reactions(p, state_.bonds);
      for (unsigned int i = 0; i < p.size(); ++i) {
        if (!state_.is_owned(i))
          continue;
        const auto du = u_now_[i] - u_last_[i];
        if (state_.free[i])
          lost_work += 0.5 * ((forces_before_[i] - p.force(i)) * du);
        else if (!reactions.empty())
          lost_work += 0.5 * ((reactions_before_[i] - reactions[i]) * du);
      }
    }
    fracture_ += stored_before_ - stored_ + lost_work;
    ++breaking_passes_;
  }
}

template <int dim>
void ParticleEnergy<dim>::after_update(double time, double dt, double h, double damping) {
  if (!on_)
    return;
  if (state_.n_free_particles() == 0)
    stored_ = 0;
  const auto& p = state_.particles;
  fem::ExplicitEnergy::Step step;
  // u_n − u_{n−1} = dt_back v_{n−½}, h = ½ (dt_back + dt): steps differ where a run lands on
  // its output times (dt_back = dt at the first step).
  const double dt_back = 2 * h - dt;
  for (unsigned int i = 0; i < p.size(); ++i) {
    if (!state_.free[i] || !state_.is_owned(i) || i >= velocity_before_.size())
      continue;
    for (unsigned int d = 0; d < dim; ++d) {
      const double fe = p.external_force(i)[d];
      step.add(p.mass(i), velocity_before_[i][d], p.velocity(i)[d], dt, h, p.force(i)[d] + fe, fe,
               p.is_fixed(i, d), damping);
    }
  }
  scale_back(step, dt_back / dt);
  account_.time = time;
  account_.external.add(step.external_back + step.prescribed_back,
                        step.external_forward + step.prescribed_forward);
  account_.damping.add(step.damping_back, step.damping_forward);
  account_.interface.add(0, 0);
  account_.internal.add(0, 0);
  account_.kinetic = step.kinetic;
  account_.kinetic_central = step.kinetic_central;
  account_.strain = stored_;
  account_.valid = true;
}

template class ParticleEnergy<2>;
template class ParticleEnergy<3>;

} // namespace spinesim::coupling
