// Quadrature-point states of MechanicsSolver: reading them, committing them, and the
// threaded refresh that brings them to the current displacement on the linear explicit path.

#include "fem/mechanics_solver.h"

#include "base/exceptions.h"
#include "fem/mean_dilatation.h"

#include <deal.II/fe/fe_values.h>

#include <exception>

namespace spinesim::fem {

using namespace dealii;
using materials::Tensor2;

template <int dim>
ArrayView<const QuadraturePointData>
MechanicsSolver<dim>::quadrature_point_data(const CellIterator& cell) const {
  refresh_states();
  const unsigned int nq = quadrature_.size();
  return ArrayView<const QuadraturePointData>(committed_.data() + cell->active_cell_index() * nq,
                                              nq);
}

template <int dim>
void MechanicsSolver<dim>::get_cell_values(const VectorType& ghosted, const CellIterator& cell,
                                           std::vector<double>& values) const {
  Assert(ghosted.trilinos_vector().Map().SameAs(u_ghost_.trilinos_vector().Map()),
         ExcMessage("get_cell_values reads vectors with the layout of displacement()"));
  const unsigned int n = fe_.n_dofs_per_cell();
  values.resize(n);
  const double* x = ghosted.trilinos_vector()[0];
  const int* lids = &cell_lids_[cell->active_cell_index() * n];
  for (unsigned int i = 0; i < n; ++i) {
    AssertThrow(lids[i] >= 0, ExcMessage("get_cell_values on a cell that is neither locally "
                                         "owned nor a ghost"));
    values[i] = x[lids[i]];
  }
}

template <int dim>
void MechanicsSolver<dim>::refresh_states() const {
  // The linear explicit path skips the point-wise update: bring stresses to the current u.
  // Points are independent, so the threads share the cells. Only that path leaves states stale
  // (no temperature, so dT = 0), and on it trial_ equals committed_ away from the points
  // refreshed here (reset after every matrix assembly): copying those is commit_history().
  if (!states_stale_)
    return;
  Assert(!temperature_field_ && !temperature_change_, ExcInternalError());
  std::vector<CellIterator> cells;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      cells.push_back(cell);
  auto& trial = const_cast<std::vector<QuadraturePointData>&>(trial_);
  auto& committed = const_cast<std::vector<QuadraturePointData>&>(committed_);
  const unsigned int nq = quadrature_.size();
  const long n = static_cast<long>(cells.size());
  std::exception_ptr failure; // the first one; exceptions must not leave a parallel region
#pragma omp parallel if (n > 256)
  {
    const bool bbar = prm_.volumetric_locking == "bbar"; // H̄ as assemble() forms it
    FEValues<dim> fe_values(*mapping_, fe_, quadrature_,
                            bbar ? update_gradients | update_JxW_values : update_gradients);
    MeanDilatation<dim> mean_dilatation;
    std::vector<unsigned int> comp(fe_.n_dofs_per_cell());
    for (unsigned int i = 0; i < comp.size(); ++i)
      comp[i] = fe_.system_to_component_index(i).first;
    const FEValuesExtractors::Vector displacements(0);
    std::vector<Tensor<2, dim>> grads(nq);
    std::vector<double> local;
#pragma omp for schedule(dynamic, 64)
    for (long k = 0; k < n; ++k) {
      const auto& cell = cells[k];
      try {
        fe_values.reinit(cell);
        get_cell_values(u_ghost_, cell, local);
        fe_values[displacements].get_function_gradients_from_local_dof_values(local, grads);
        double average_dilatation = 0;
        if (bbar) {
          mean_dilatation.reinit(fe_values, comp);
          average_dilatation = mean_dilatation.average_dilatation(grads);
        }
        const materials::ConstitutiveLaw& law = cell_material(cell);
        for (unsigned int q = 0; q < nq; ++q) {
          const std::size_t idx = cell->active_cell_index() * nq + q;
          Tensor2 H = padded_gradient<dim>(grads[q]);
          if (bbar)
            MeanDilatation<dim>::project(H, average_dilatation);
          try {
            point_update_(law, H, 0.0, committed_[idx], trial[idx], nullptr);
          } catch (const NumericalFailure& e) {
            throw NumericalFailure(e.what_failed(), quadrature_point_location<dim>(cell, q),
                                   e.hint());
          }
        }
      } catch (...) {
#pragma omp critical(spinesim_refresh_states)
        if (!failure)
          failure = std::current_exception();
      }
    }
  }
  if (failure)
    std::rethrow_exception(failure);
#pragma omp parallel for schedule(static) if (n > 256)
  for (long k = 0; k < n; ++k) {
    const std::size_t first = cells[k]->active_cell_index() * nq;
    std::copy(trial_.begin() + first, trial_.begin() + first + nq, committed.begin() + first);
  }
  states_stale_ = false;
}

template <int dim>
void MechanicsSolver<dim>::commit_history() {
  committed_ = trial_;
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template ArrayView<const QuadraturePointData> MechanicsSolver<dim>::quadrature_point_data(       \
      const CellIterator&) const;                                                                  \
  template void MechanicsSolver<dim>::get_cell_values(const VectorType&, const CellIterator&,      \
                                                      std::vector<double>&) const;                 \
  template void MechanicsSolver<dim>::refresh_states() const;                                      \
  template void MechanicsSolver<dim>::commit_history();
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
