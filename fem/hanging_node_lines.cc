#include "fem/hanging_node_lines.h"

#include <deal.II/base/mpi.h>

#include <Epetra_Import.h>

namespace spinesim::fem {

using namespace dealii;

void HangingNodeLines::reinit(const IndexSet& owned, const IndexSet& relevant, MPI_Comm comm,
                              std::shared_ptr<const Epetra_Import> ghost_import) {
  owned_ = owned;
  comm_ = comm;
  ghost_import_ = std::move(ghost_import);
  scratch_.reinit(owned, relevant, comm);
  lines_.clear();
}

void HangingNodeLines::build(const AffineConstraints<double>& hanging) {
  lines_.clear();
  bool local = true;
  for (const auto& line : hanging.get_lines())
    if (owned_.is_element(line.index))
      for (const auto& [master, weight] : line.entries)
        local = local && owned_.is_element(master);
  masters_owned_ = Utilities::MPI::min(local ? 1 : 0, comm_) == 1;
  const auto& ghost_map = scratch_.trilinos_vector().Map();
  for (const auto& line : hanging.get_lines()) {
    if (!owned_.is_element(line.index))
      continue;
    Line h{static_cast<unsigned int>(owned_.index_within_set(line.index)), {}, line.inhomogeneity};
    for (const auto& [master, weight] : line.entries) {
      const int index = masters_owned_
                            ? static_cast<int>(owned_.index_within_set(master))
                            : ghost_map.LID(static_cast<TrilinosWrappers::types::int_type>(master));
      AssertThrow(index >= 0, ExcMessage("hanging-node master outside the relevant DoFs"));
      h.masters.emplace_back(static_cast<unsigned int>(index), weight);
    }
    lines_.push_back(std::move(h));
  }
}

void HangingNodeLines::distribute(VectorType& vector) const {
  double* x = vector.begin();
  const double* masters = x;
  if (!masters_owned_) { // collective: every rank takes this branch or none
    scratch_.trilinos_vector().Import(vector.trilinos_vector(), *ghost_import_, Insert);
    masters = scratch_.trilinos_vector()[0];
  }
  for (const auto& line : lines_) {
    double value = line.inhomogeneity;
    for (const auto& [master, weight] : line.masters)
      value += weight * masters[master];
    x[line.local] = value;
  }
}

} // namespace spinesim::fem
