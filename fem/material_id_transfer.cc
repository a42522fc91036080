#include "fem/material_id_transfer.h"

#include <deal.II/grid/grid_tools.h>

namespace spinesim::fem {

template <int dim>
MaterialIdTransfer<dim>::MaterialIdTransfer(
    dealii::parallel::distributed::Triangulation<dim>& triangulation)
    : tria_(triangulation) {}

template <int dim>
void MaterialIdTransfer<dim>::collect() {
  ids_.reinit(tria_.n_active_cells());
  for (const auto& cell : tria_.active_cell_iterators())
    if (cell->is_locally_owned())
      ids_[cell->active_cell_index()] = cell->material_id();
  transfer_ = std::make_unique<
      dealii::parallel::distributed::CellDataTransfer<dim, dim, dealii::Vector<float>>>(tria_);
}

template <int dim>
void MaterialIdTransfer<dim>::prepare() {
  collect();
  transfer_->prepare_for_coarsening_and_refinement(ids_);
}

template <int dim>
void MaterialIdTransfer<dim>::prepare_for_serialization() {
  collect();
  transfer_->prepare_for_serialization(ids_);
}

template <int dim>
void MaterialIdTransfer<dim>::deserialize() {
  transfer_ = std::make_unique<
      dealii::parallel::distributed::CellDataTransfer<dim, dim, dealii::Vector<float>>>(tria_);
  dealii::Vector<float> ids(tria_.n_active_cells());
  transfer_->deserialize(ids);
  transfer_.reset();
  set_owned(ids);
}

template <int dim>
void MaterialIdTransfer<dim>::finish() {
  dealii::Vector<float> ids(tria_.n_active_cells());
  transfer_->unpack(ids);
  transfer_.reset();
  set_owned(ids);
}

template <int dim>
void MaterialIdTransfer<dim>::set_owned(const dealii::Vector<float>& ids) {
  for (const auto& cell : tria_.active_cell_iterators())
    if (cell->is_locally_owned())
      cell->set_material_id(
          static_cast<dealii::types::material_id>(ids[cell->active_cell_index()]));
  update_ghosts(tria_);
}

template <int dim>
void MaterialIdTransfer<dim>::update_ghosts(
    dealii::parallel::distributed::Triangulation<dim>& triangulation) {
  using Iterator = typename dealii::Triangulation<dim>::active_cell_iterator;
  dealii::GridTools::exchange_cell_data_to_ghosts<unsigned int, dealii::Triangulation<dim>>(
      triangulation,
      [](const Iterator& cell) { return static_cast<unsigned int>(cell->material_id()); },
      [](const Iterator& cell, const unsigned int id) { cell->set_material_id(id); });
}

template class MaterialIdTransfer<2>;
template class MaterialIdTransfer<3>;

} // namespace spinesim::fem
