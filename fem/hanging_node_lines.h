#ifndef SPINESIM_FEM_HANGING_NODE_LINES_H
#define SPINESIM_FEM_HANGING_NODE_LINES_H

// Hanging-node constraints of the owned DoFs, applied to the local array of an owned vector:
// AffineConstraints::distribute builds a ghosted copy of the vector (and an import) at every
// call, too slow for an explicit step. Masters are read from the owned entries when every
// rank owns all its masters, else from a ghosted copy made with an import kept from setup.

#include <deal.II/base/index_set.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/trilinos_vector.h>

#include <memory>
#include <utility>
#include <vector>

class Epetra_Import;

namespace spinesim::fem {

class HangingNodeLines {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;

  // The layouts of the vectors to distribute: owned and locally relevant DoFs, and the
  // owned -> relevant import. Once per mesh; collective.
  void reinit(const dealii::IndexSet& owned, const dealii::IndexSet& relevant, MPI_Comm comm,
              std::shared_ptr<const Epetra_Import> ghost_import);
  // Takes the lines of the owned DoFs that `hanging` constrains. Collective.
  void build(const dealii::AffineConstraints<double>& hanging);
  // Sets each owned constrained entry of `vector` (owned layout) to its masters' weighted sum
  // plus the inhomogeneity. Collective.
  void distribute(VectorType& vector) const;

 private:
  struct Line {
    unsigned int local; // index within the owned DoFs
    std::vector<std::pair<unsigned int, double>> masters;
    double inhomogeneity;
  };
  std::vector<Line> lines_;
  // Masters by owned index when every rank's masters are its own, else by index in the
  // ghosted layout, read from scratch_ after the import.
  bool masters_owned_ = false;
  dealii::IndexSet owned_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  std::shared_ptr<const Epetra_Import> ghost_import_;
  mutable VectorType scratch_;
};

} // namespace spinesim::fem

#endif
