#ifndef SPINESIM_COUPLING_MLS_INTERFACE_H
#define SPINESIM_COUPLING_MLS_INTERFACE_H

// The FEM side of the overlapping splice: DoFs shared by an active and a converted cell are
// driven by a linear moving-least-squares fit of the free particles around them (mls_fit.h),
// so the FEM sees complete element patches and an affine field creates no force.
//
// Under finite strain a DoF is driven by the fit plus the offset it has from the fit when the
// interface is built (after each conversion): the particles continue the FEM's field, and
// where that field is far from affine over the fit's support (a crushed corner) the fit
// misses the node's value by a fraction of a cell. Snapping the node onto the fit would move
// it within one step, with the force of its crushed cells, and distort its neighbours into
// conversion in turn; the offset keeps it where it is and moves it with the particles from
// then on. Under small strain the miss is second order in the cell size and the node snaps
// onto the fit, which keeps the patch tests exact after a conversion at a relaxed state.

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
    double offset = 0; // the DoF's value less the fit when the interface was built [m]
  };

  explicit MlsInterface(CouplingState<dim>& state) : state_(state) {}

  // The interface DoFs of the current split and their fits (locally relevant cells), with zero
  // offsets.
  void rebuild();
  // Each DoF's offset from its fit (finite strain; zero under small strain). Needs the
  // current displacements of every particle in the fits: after the halo exchange.
  void set_offsets();
  // Zero offsets, for a state made affine by hand (a patch test).
  void clear_offsets();
  // The driven values from the particle displacements, handed to the FEM.
  void update();
  // The driven displacement of one interface DoF: the fit plus the DoF's offset [m].
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
