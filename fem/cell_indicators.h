#ifndef SPINESIM_FEM_CELL_INDICATORS_H
#define SPINESIM_FEM_CELL_INDICATORS_H

// Per-cell state of a mechanics solution, for output and for deciding which elements to hand
// over to particles: geometric health of the deformed cell, plasticity, a damage measure and
// the cell's stable explicit time step. Every vector has one entry per active cell (index =
// active_cell_index); only locally owned cells are filled, others are 0.

#include "fem/mechanics_solver.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/lac/vector.h>

namespace spinesim::fem {

// The failure thresholds, the same in 2-D and 3-D.
struct CellIndicatorsParameters {
  double critical_principal_strain = 0.02;  // [-]
  double critical_principal_stress = 100e6; // [Pa]
  double cfl_safety_factor = 0.5;           // [-]
  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class CellIndicators {
 public:
  using Parameters = CellIndicatorsParameters;

  explicit CellIndicators(const Parameters& parameters = Parameters()) : prm_(parameters) {}

  // Evaluates everything at the solver's current (committed) state.
  // Without `with_state` the point-wise states are not read (no stress refresh): principal
  // strains come from the in-plane displacement gradient, plastic strain and stress are 0.
  void compute(const MechanicsSolver<dim>& solver, bool with_state = true);
  // The subset a conversion check needs: only the cells flagged in `cells` (by active cell
  // index; others stay 0) and, without `geometry`, no Jacobian ratio, aspect ratio or stable
  // step (those need the vertices and the mapping's Jacobians: the larger part of the cost).
  void compute(const MechanicsSolver<dim>& solver, bool with_state, const std::vector<bool>& cells,
               bool geometry);

  // min over vertices and quadrature points of det J (deformed) / max of the same [-];
  // 1 for an undistorted parallelogram, <= 0 when the cell is inverted.
  dealii::Vector<float> min_jacobian_ratio;
  dealii::Vector<float> inverted; // 1 if some det J <= 0, else 0
  // Longest over shortest edge of the deformed cell [-].
  dealii::Vector<float> aspect_ratio;
  dealii::Vector<float> equivalent_plastic_strain; // cell average [-]
  dealii::Vector<float> max_principal_strain;      // max over quadrature points [-]
  dealii::Vector<float> max_principal_stress;      // max over quadrature points [Pa]
  // max(ε₁ / critical strain, σ₁ / critical stress): >= 1 means the cell has failed [-].
  dealii::Vector<float> damage;
  // Safety × shortest deformed edge / (degree × P-wave speed) [s].
  dealii::Vector<float> stable_time_step;

  // Global counts over all ranks.
  unsigned int n_inverted() const { return n_inverted_; }
  unsigned int n_damaged() const { return n_damaged_; }

 private:
  Parameters prm_;
  unsigned int n_inverted_ = 0, n_damaged_ = 0;
};

} // namespace spinesim::fem

#endif
