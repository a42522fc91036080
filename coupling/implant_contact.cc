#include "coupling/implant_contact.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spinesim::coupling {

using namespace dealii;

namespace implant_contact_detail {
// The particle's reach: half the lattice spacing (the cube it stands for) [m].
double reach(double spacing) {
  return 0.5 * spacing;
}
} // namespace implant_contact_detail

template <int dim>
void ImplantContact<dim>::resize(unsigned int n) {
  stick_.resize(n);
  trial_stick_.resize(n);
  stuck_.resize(n, 0);
}

template <int dim>
void ImplantContact<dim>::rebuild(const std::vector<unsigned int>& targets) {
  candidates_.clear();
  if (!on())
    return;
  const auto& particles = state_.particles;
  const unsigned int n = particles.size();
  resize(n);
  const double horizon = state_.horizon(), r2 = horizon * horizon;
  const double reach = implant_contact_detail::reach(state_.spacing);
  std::vector<std::uint8_t> kept(n, 0);
  for (unsigned int i = 0; i < n; ++i) {
    if (!state_.free[i])
      continue;
    const Point<dim>& X = particles.reference_position(i);
    double best = r2;
    int nearest = -1;
    for (const unsigned int g : targets) {
      const double d2 = X.distance_square(particles.reference_position(g));
      if (d2 <= best) {
        best = d2;
        nearest = static_cast<int>(g);
      }
    }
    if (nearest < 0)
      continue;
    Vector normal;
    const double gap = state_.prm.implant_surface(X, normal) - reach;
    if (!std::isfinite(gap))
      throw NumericalFailure("implant contact: the surface's distance is not finite",
                             "particle " + std::to_string(i) + " at its reference position",
                             "check the implant's geometry (a closed surface)");
    candidates_.push_back({i, static_cast<unsigned int>(nearest), std::min(gap, 0.0)});
    kept[i] = 1;
    // A new candidate's stick point: where it is now against the implant (the layers are
    // rebuilt at equilibrium, so this is a committed state).
    if (!stuck_[i]) {
      stick_[i] = trial_stick_[i] =
          particles.displacement(i) - particles.displacement(static_cast<unsigned int>(nearest));
      stuck_[i] = 1;
    }
  }
  for (unsigned int i = 0; i < n; ++i)
    if (!kept[i])
      stuck_[i] = 0;
}

template <int dim>
double ImplantContact<dim>::penalty(unsigned int i) const {
  const auto& particles = state_.particles;
  const double E = (*state_.laws)[particles.material_id(i)].youngs_modulus;
  return state_.prm.implant_contact_stiffness * E * particles.volume(i) /
         (state_.spacing * state_.spacing);
}

template <int dim>
void ImplantContact<dim>::add_forces(std::vector<Vector>& ghost_forces) {
  active_ = 0;
  total_ = Vector();
  couple_ = Tensor<2, dim>();
  deepest_ = 0;
  if (!on())
    return;
  auto& particles = state_.particles;
  const double reach = implant_contact_detail::reach(state_.spacing);
  const double mu = state_.prm.implant_friction;
  for (const auto& c : candidates_) {
    const unsigned int i = c.particle;
    if (!state_.is_owned(i))
      continue;
    // The particle's displacement relative to the implant next to it, and its centre in the
    // implant's reference frame.
    const Vector w = particles.displacement(i) - particles.displacement(c.ghost);
    const Point<dim> X = particles.reference_position(i) + w;
    Vector n;
    const double gap = state_.prm.implant_surface(X, n) - reach;
    // Out of contact, the stick point follows the particle: a slip is measured from where the
    // last equilibrium left it.
    trial_stick_[i] = w;
    if (!std::isfinite(gap) || !(gap < c.reference_gap)) {
      if (!std::isfinite(gap))
        throw NumericalFailure("implant contact: the surface's distance is not finite",
                               "particle " + std::to_string(i) + ", " + std::to_string(w.norm()) +
                                   " m from the implant's nearest ghost",
                               "the particles' displacements diverged: a smaller load step or "
                               "a lower Coupling/Implant contact stiffness");
      continue;
    }
    const double k = penalty(i);
    const double depth = c.reference_gap - gap;
    const double normal_force = k * depth;
    Vector f = normal_force * n;
    if (mu > 0.0) {
      // Return map of the stick spring: the trial force from the committed stick point
      // (where the last equilibrium left the particle, if it was not in contact then),
      // limited to μ f_n.
      const Vector s = w - stick_[i];
      const Vector s_t = s - (s * n) * n;
      Vector f_t = -k * s_t;
      const double limit = mu * normal_force, magnitude = f_t.norm();
      if (magnitude > limit)
        f_t *= limit / magnitude;
      trial_stick_[i] = w + f_t / k; // the stick point that gives f_t
      f += f_t;
    }
    particles.force(i) += f;
    ghost_forces[c.ghost] -= f;
    total_ -= f;
    couple_ +=
        outer_product(particles.reference_position(i) - particles.reference_position(c.ghost), f);
    deepest_ = std::max(deepest_, depth);
    ++active_;
  }
}

template <int dim>
void ImplantContact<dim>::commit() {
  for (const auto& c : candidates_)
    if (state_.is_owned(c.particle)) {
      stick_[c.particle] = trial_stick_[c.particle];
    }
}

template <int dim>
void ImplantContact<dim>::add_stiffness_bound(std::vector<double>& bound) const {
  if (!on())
    return;
  for (const auto& c : candidates_)
    if (c.particle < bound.size())
      bound[c.particle] += 2.0 * penalty(c.particle) / state_.particles.volume(c.particle);
}

template <int dim>
std::vector<std::pair<unsigned int, Tensor<1, dim>>> ImplantContact<dim>::stick_points() const {
  std::vector<std::pair<unsigned int, Vector>> mine;
  for (const auto& c : candidates_)
    if (state_.is_owned(c.particle) && stuck_[c.particle])
      mine.emplace_back(c.particle, stick_[c.particle]);
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return mine;
  std::vector<std::pair<unsigned int, Vector>> all;
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    all.insert(all.end(), part.begin(), part.end());
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return all;
}

template <int dim>
void ImplantContact<dim>::restore(const std::vector<std::pair<unsigned int, Vector>>& points) {
  // rebuild() gave every candidate its current place; the file's points replace those.
  resize(state_.particles.size());
  for (const auto& [i, s] : points) {
    if (i >= stuck_.size())
      throw InvalidInput("coupling checkpoint",
                         "a contact stick point names particle " + std::to_string(i) + " of " +
                             std::to_string(stuck_.size()),
                         "a checkpoint written by this program");
    stick_[i] = trial_stick_[i] = s;
    stuck_[i] = 1;
  }
}

template class ImplantContact<2>;
template class ImplantContact<3>;

} // namespace spinesim::coupling
