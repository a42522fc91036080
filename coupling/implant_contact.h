#ifndef SPINESIM_COUPLING_IMPLANT_CONTACT_H
#define SPINESIM_COUPLING_IMPLANT_CONTACT_H

// Contact between the free particles and an implant meshed with the bone, against the
// implant's true surface (CouplingParameters::implant_surface: the signed distance in the
// implant's reference frame, negative inside), so that failed bone cannot pass through the
// implant whatever its bonds still hold. It rides on the implant joint (implant_joint.h): the
// implant's motion near a particle is that of its nearest ghost in an implant cell, and the
// reaction goes back to the implant's FEM through that ghost, in the joint's force pass.
//
// A particle stands for a cube of bone of side h (the lattice spacing): it touches the implant
// when its centre comes within h/2 of the surface. With g_i the distance of the particle's
// centre, carried into the implant's frame by the ghost's displacement, from the surface, less
// h/2, and g0_i = min(g_i at the reference configuration, 0) (lattice points next to a thread
// may start inside the cubes' reach of it), the normal penalty force is
//   f_n = κ_n (g0_i − g_i) n  when g_i < g0_i,   κ_n = Implant contact stiffness × E_i V_i / h²,
// n the surface's outward normal and E_i V_i / h² the stiffness of the particle's cube under a
// face load (E_i h in 3-D): the penalty adds, in series with the bone next to the implant, the
// compliance of a bone layer h / (Implant contact stiffness) thick. The default, 2, is the half
// cube between the particle's centre and the surface, which the contact stands in for. Friction is
// Coulomb's with an elastic stick of the same stiffness and a return map (Wriggers 2006,
// Computational Contact Mechanics, sec. 5.2 and 10.3): the tangential slip s_t of the particle
// against the ghost since its committed stick point gives the trial force −κ_n s_t, limited to μ
// |f_n|; the stick point follows a sliding particle and is committed with the material history,
// once a load step is in equilibrium. Out of contact the stick point is where the particle is, so a
// slip is measured from the last equilibrium. Both sides see equal and opposite forces, so the pair
// makes and loses no force; the reaction acts at the ghost, within a horizon of the particle, which
// the coupled body's virial balance counts (a couple of about h × the contact force).
//
// MPI: particles are replicated; each rank pushes the free particles it owns, and the joint
// sums the ghosts' reactions over the ranks with its own.

#include "coupling/coupling_state.h"

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class ImplantContact {
 public:
  using Vector = dealii::Tensor<1, dim>;

  explicit ImplantContact(CouplingState<dim>& state) : state_(state) {}

  // Whether the run has an implant surface and a contact stiffness above zero.
  bool on() const {
    return static_cast<bool>(state_.prm.implant_surface) &&
           state_.prm.implant_contact_stiffness > 0.0;
  }
  // After the layers changed: each free particle within a horizon of a ghost in an implant
  // cell (`targets`, particle indices) pairs with the nearest one; its reference gap is taken.
  // Stick points of particles that stay candidates are kept.
  void rebuild(const std::vector<unsigned int>& targets);
  // Adds the contact forces of the owned candidates to the particles' forces and their
  // reactions to `ghost_forces` (indexed by particle) at the current state.
  void add_forces(std::vector<Vector>& ghost_forces);
  // The trial stick points become the committed ones (a load step in equilibrium).
  void commit();
  // Contact stiffness per particle volume to add to the particles' stiffness bound, for the
  // stable step: κ_n (1 + 1) / V_i on every candidate (normal and stick), 0 elsewhere [N/m^4].
  void add_stiffness_bound(std::vector<double>& bound) const;

  // This rank's figures of the last add_forces(): active pairs, the sum of the contact
  // forces on the implant [N], the deepest penetration beyond the reference gap [m].
  unsigned int active_pairs() const { return active_; }
  Vector force_on_implant() const { return total_; }
  double deepest_penetration() const { return deepest_; }
  // Σ (X_i − X_g) ⊗ f_i over this rank's active pairs (reference positions of the particle and
  // its ghost, f_i the force on the particle): the couple the transfer to the ghost adds to the
  // coupled body's virial [N m].
  dealii::Tensor<2, dim> transfer_couple() const { return couple_; }
  unsigned int n_candidates() const { return static_cast<unsigned int>(candidates_.size()); }

  // The committed stick points (particle index, point [m]), from their owners, on every rank,
  // for a checkpoint (collective); restore() puts them back after the layers are rebuilt.
  std::vector<std::pair<unsigned int, Vector>> stick_points() const;
  void restore(const std::vector<std::pair<unsigned int, Vector>>& points);
  // Bytes of the candidates and the per-particle stick arrays [B].
  std::size_t memory_bytes() const {
    return candidates_.capacity() * sizeof(Candidate) +
           (stick_.capacity() + trial_stick_.capacity()) * sizeof(Vector) + stuck_.capacity();
  }

 private:
  struct Candidate {
    unsigned int particle = 0, ghost = 0;
    double reference_gap = 0; // g0 [m]
  };
  CouplingState<dim>& state_;
  std::vector<Candidate> candidates_;
  // Per particle: the committed and trial stick points (relative displacement particle −
  // ghost [m]) and whether one is set (the candidates').
  std::vector<Vector> stick_, trial_stick_;
  std::vector<std::uint8_t> stuck_;
  unsigned int active_ = 0;
  Vector total_;
  double deepest_ = 0;
  dealii::Tensor<2, dim> couple_;
  double penalty(unsigned int particle) const; // κ_n [N/m]
  void resize(unsigned int n);
};

} // namespace spinesim::coupling

#endif
