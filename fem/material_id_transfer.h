#ifndef SPINESIM_FEM_MATERIAL_ID_TRANSFER_H
#define SPINESIM_FEM_MATERIAL_ID_TRANSFER_H

// Keeps the material ids of active cells through refinement, coarsening and repartitioning of
// a distributed triangulation. p4est stores only the forest: a cell that moves to another
// rank when execute_coarsening_and_refinement() repartitions arrives with its coarse cell's
// id, so ids set on refined cells (removed bone, per-cell materials) would silently revert.
// Children take their parent's id; coarsened cells must agree (CellDataTransfer's defaults).
//
//   MaterialIdTransfer<dim> keep(tria);
//   keep.prepare();                  // after the flags are final, before execution
//   tria.execute_coarsening_and_refinement();
//   keep.finish();                   // owned cells from the transfer, ghosts from their owners
//
// The same through a checkpoint (tria.save() / load() keep the forest only):
//   keep.prepare_for_serialization(); tria.save(file);     // keep alive until save() returns
//   tria.load(file); keep.deserialize();                    // in the order of the other data

#include <deal.II/distributed/cell_data_transfer.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/lac/vector.h>

#include <memory>
#include <vector>

namespace spinesim::fem {

template <int dim>
class MaterialIdTransfer {
 public:
  explicit MaterialIdTransfer(dealii::parallel::distributed::Triangulation<dim>& triangulation);
  void prepare();
  void finish();
  void prepare_for_serialization();
  void deserialize();
  // Copies the ids of locally owned cells to the ghost cells of other ranks (collective).
  static void update_ghosts(dealii::parallel::distributed::Triangulation<dim>& triangulation);

 private:
  // The owned cells' ids into ids_, and a new transfer for them.
  void collect();
  // Owned cells' ids from `ids` (by active cell index), then the ghosts' from their owners.
  void set_owned(const dealii::Vector<float>& ids);

  dealii::parallel::distributed::Triangulation<dim>& tria_;
  dealii::Vector<float> ids_; // ids below 2^24 are exact in float
  std::unique_ptr<dealii::parallel::distributed::CellDataTransfer<dim, dim, dealii::Vector<float>>>
      transfer_;
};

} // namespace spinesim::fem

#endif
