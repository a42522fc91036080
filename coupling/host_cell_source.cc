#include "coupling/host_cell_source.h"

#include <deal.II/base/mpi.h>

namespace spinesim::coupling {

template <int dim>
double host_cell_power(const CouplingState<dim>& state, const std::vector<double>& energy,
                       double factor, double elapsed, dealii::Vector<double>& power) {
  double local = 0; // energy gathered by this rank's host cells [J]
  for (const auto& [cell, row] : state.free_cells) {
    double sum = 0;
    for (const int i : row)
      if (i >= 0 && static_cast<unsigned int>(i) < energy.size())
        sum += energy[i];
    power(cell->active_cell_index()) = factor * sum / (cell->measure() * elapsed);
    local += sum;
  }
  return dealii::Utilities::MPI::sum(local, state.fem.mpi_communicator());
}

template double host_cell_power(const CouplingState<2>&, const std::vector<double>&, double, double,
                                dealii::Vector<double>&);
template double host_cell_power(const CouplingState<3>&, const std::vector<double>&, double, double,
                                dealii::Vector<double>&);

} // namespace spinesim::coupling
