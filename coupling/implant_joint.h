#ifndef SPINESIM_COUPLING_IMPLANT_JOINT_H
#define SPINESIM_COUPLING_IMPLANT_JOINT_H

// An implant meshed with the bone (a pedicle screw), next to bone that turned into particles.
// The implant's cells never convert (CouplingParameters::unconverted_material_ids); the overlap
// splice would drive the implant's nodes next to the particles by their moving-least-squares
// fit, imposing the bone's motion on a body hundreds of times stiffer, whose stiffness then
// turns the fit's errors into large forces. The joint instead splits the interface the way a
// Dirichlet–Neumann coupling of a stiff and a soft body does: the particles are bonded to the
// implant's ghosts, which follow the implant's FEM displacement (the soft side sees the stiff
// side's motion), and the implant's FEM takes back the forces the free particles put on those
// ghosts (the stiff side sees the soft side's forces), spread by Nᵀ to its DoFs. The forces are
// split family by family (ParticleMethod::joint_reactions), so what the implant receives is
// exactly the opposite of what the particles receive from it: no net force is made or lost at
// the joint. Bonds between the particles and the implant's ghosts break by the bone's criteria,
// which is how the bone lets go of the implant.
//
// Interior ghosts of the implant (families of ghosts only) are the FEM's: their forces are
// not counted, so the implant's stiffness is not doubled. On several ranks each rank sums the
// families whose centre it owns; the sums meet by one reduction over the ghosts in implant
// cells per force pass.

#include "coupling/coupling_state.h"
#include "coupling/implant_contact.h"

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/lac/trilinos_vector.h>

#include <cstdint>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class ImplantJoint {
 public:
  using Vector = dealii::Tensor<1, dim>;
  using StepForces = typename fem::MechanicsSolver<dim>::StepForces;

  explicit ImplantJoint(CouplingState<dim>& state) : state_(state), contact_(state) {}

  // Whether the run holds an implant (unconverted material ids) with the overlap splice.
  bool on() const {
    return !state_.prm.unconverted_material_ids.empty() && state_.prm.splice == "overlap";
  }
  // After the layers changed: which ghosts sit in implant cells (collective). InvalidInput if
  // the particle method cannot split its forces by family.
  void rebuild();
  unsigned int n_targets() const { return static_cast<unsigned int>(targets_.size()); }
  // After the particle force pass: the implant ghosts' reactions, with the contact's
  // (implant_contact.h) added to the particles and their ghosts, on every rank, and spread to
  // the FEM's owned DoFs (collective).
  void take_particle_forces();
  // The FEM's step force hook at the same state: the reactions onto the implant's DoFs that
  // move. A prescribed DoF's share is what the particles push straight into the support:
  // prescribed_force() sums it.
  void add_reactions(const StepForces& forces);
  // The reactions' virial Σ (X_g − origin) ⊗ r_g at the ghosts' reference positions (= the
  // DoFs' by Σ_a N_a X_a = X), on every rank.
  dealii::Tensor<2, dim> virial(const dealii::Point<dim>& origin) const;
  // The part of the last add_reactions() on prescribed DoFs, summed over the ranks' owned
  // DoFs of this rank (sum it over the ranks).
  Vector prescribed_force() const { return prescribed_; }
  // The part of it on the free DoFs when the FEM's residual holds it (StepForces::
  // seen_by_reactions: the residual's rest is then net of it), this rank's.
  Vector force_in_residual() const { return into_residual_; }
  // Contact between the free particles and the implant's true surface, through its ghosts.
  ImplantContact<dim>& contact() { return contact_; }
  const ImplantContact<dim>& contact() const { return contact_; }
  // Bytes of the targets, the per-particle flags and the contact's arrays [B].
  std::size_t memory_bytes() const {
    return targets_.capacity() * sizeof(unsigned int) + is_target_.capacity() +
           reactions_.capacity() * sizeof(Vector) + contact_.memory_bytes();
  }

 private:
  CouplingState<dim>& state_;
  std::vector<unsigned int> targets_;   // particle indices of ghosts in implant cells
  std::vector<std::uint8_t> is_target_; // per particle
  std::vector<Vector> reactions_;       // per target, summed over the ranks [N]
  dealii::TrilinosWrappers::MPI::Vector fem_reactions_; // owned DoFs, writable ghosts
  std::vector<double> owned_values_;                    // owned local order
  std::vector<unsigned int> component_;                 // of each owned DoF
  Vector prescribed_, into_residual_;
  ImplantContact<dim> contact_;
};

} // namespace spinesim::coupling

#endif
