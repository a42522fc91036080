#ifndef SPINESIM_COUPLING_MLS_INTERFACE_H
#define SPINESIM_COUPLING_MLS_INTERFACE_H

// The FEM side of the overlapping splice: DoFs shared by an active and a converted cell are
// driven by a linear moving-least-squares fit of the free particles around them (mls_fit.h),
// so the FEM sees complete element patches and an affine field creates no force.

#include "coupling/coupling_state.h"

#include <deal.II/base/types.h>

#include <utility>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class MlsInterface {
 public:
  struct Dof {
    dealii::types::global_dof_index dof;
    unsigned int component;
    std::vector<std::pair<unsigned int, double>> weights; // free particle, MLS shape value
  };

  explicit MlsInterface(CouplingState<dim>& state) : state_(state) {}

  // The interface DoFs of the current split and their fits (locally relevant cells).
  void rebuild();
  // The driven values from the particle displacements, handed to the FEM.
  void update();
  // The fitted displacement of one interface DoF [m].
  double value(const Dof& entry) const;
  // In ascending DoF order.
  const std::vector<Dof>& dofs() const { return dofs_; }

 private:
  CouplingState<dim>& state_;
  std::vector<Dof> dofs_;
  std::vector<double> values_;
  bool registered_ = false; // the solver knows the interface DoFs
};

} // namespace spinesim::coupling

#endif
