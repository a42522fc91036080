// Checkpoints of MechanicsSolver: the mesh and the displacement and velocity through p4est,
// the committed point states attached to the cells, and time and degree in a small text file.

#include "fem/mechanics_solver.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/solution_transfer.h>

#include <cmath>
#include <cstring>
#include <fstream>

namespace spinesim::fem {

using namespace dealii;

template <int dim>
void MechanicsSolver<dim>::prepare_for_serialization(const std::string& filename) const {
  refresh_states();
  ScopedTime timer(timings_.checkpoint);
  auto& tria = const_cast<parallel::distributed::Triangulation<dim>&>(tria_);
  // The transfer must live until the triangulation is saved.
  serialization_transfer_ =
      std::make_unique<parallel::distributed::SolutionTransfer<dim, VectorType>>(dof_handler_);
  serialization_transfer_->prepare_for_serialization(
      std::vector<const VectorType*>{&u_ghost_, &v_ghost_});
  const unsigned int nq = quadrature_.size();
  tria.register_data_attach(
      [this, nq](const typename Triangulation<dim>::cell_iterator& cell,
                 const typename Triangulation<dim>::CellStatus) {
        std::vector<double> values(nq * quadrature_point_doubles);
        for (unsigned int q = 0; q < nq; ++q)
          pack(committed_[cell->active_cell_index() * nq + q],
               values.data() + q * quadrature_point_doubles);
        std::vector<char> bytes(values.size() * sizeof(double));
        std::memcpy(bytes.data(), values.data(), bytes.size());
        return bytes;
      },
      /*returns_variable_size_data=*/false);
  if (Utilities::MPI::this_mpi_process(comm_) == 0) {
    std::ofstream out(filename + ".solver");
    out.precision(17);
    // Version 2 adds the last explicit step (the next step's velocity interval needs it).
    out << "spinesim_mechanics 2\n"
        << time_ << " " << loaded_ << " " << prm_.fe_degree << " " << previous_step_ << "\n";
  }
}

template <int dim>
void MechanicsSolver<dim>::save_checkpoint(const std::string& filename) const {
  prepare_for_serialization(filename);
  ScopedTime timer(timings_.checkpoint);
  const_cast<parallel::distributed::Triangulation<dim>&>(tria_).save(filename);
  serialization_transfer_.reset();
}

template <int dim>
void MechanicsSolver<dim>::deserialize(const std::string& filename) {
  ScopedTime timer(timings_.checkpoint);
  serialization_transfer_.reset();
  std::ifstream in(filename + ".solver");
  // Read into locals: a rejected file leaves the solver as it was.
  std::string tag;
  int version = 0;
  unsigned int degree = 0;
  double time = 0, previous_step = -1; // version 1 did not keep the step: a constant one's
  bool loaded = false;
  if (!(in >> tag >> version >> time >> loaded >> degree) || tag != "spinesim_mechanics")
    throw InvalidInput(filename + ".solver", "missing or unreadable solver checkpoint",
                       "a file written by MechanicsSolver::save_checkpoint");
  if (version < 1 || version > 2)
    throw InvalidInput(filename + ".solver", "solver checkpoint version " + std::to_string(version),
                       "version 1 or 2 (a file written by MechanicsSolver::save_checkpoint)");
  if (version == 2 && !(in >> previous_step && std::isfinite(previous_step)))
    throw InvalidInput(filename + ".solver", "the last explicit step is missing or unreadable",
                       "a file written by MechanicsSolver::save_checkpoint");
  if (degree != prm_.fe_degree)
    throw InvalidInput("Finite element degree", "checkpoint has degree " + std::to_string(degree),
                       "the degree the checkpoint was written with");
  time_ = time;
  loaded_ = loaded;
  previous_step_ = previous_step;
  previous_time_ = target_time_ = time_;
  setup();
  parallel::distributed::SolutionTransfer<dim, VectorType> transfer(dof_handler_);
  std::vector<VectorType*> vectors{&u_, &v_};
  transfer.deserialize(vectors);
  const unsigned int nq = quadrature_.size();
  const unsigned int handle = tria_.register_data_attach(
      [](const typename Triangulation<dim>::cell_iterator&,
         const typename Triangulation<dim>::CellStatus) { return std::vector<char>(); },
      false);
  tria_.notify_ready_to_unpack(
      handle, [this, nq](const typename Triangulation<dim>::cell_iterator& cell,
                         const typename Triangulation<dim>::CellStatus,
                         const boost::iterator_range<std::vector<char>::const_iterator>& bytes) {
        std::vector<double> values(nq * quadrature_point_doubles);
        std::memcpy(values.data(), &*bytes.begin(), values.size() * sizeof(double));
        for (unsigned int q = 0; q < nq; ++q)
          unpack(values.data() + q * quadrature_point_doubles,
                 committed_[cell->active_cell_index() * nq + q]);
      });
  trial_ = committed_;
  update_ghosts();
  // Reactions need the residual at the restored state.
  assemble(false, 1.0, homogeneous_constraints());
  trial_ = committed_;
}

template <int dim>
void MechanicsSolver<dim>::load_checkpoint(const std::string& filename) {
  tria_.load(filename);
  deserialize(filename);
}

template <int dim>
typename MechanicsSolver<dim>::StateCopy MechanicsSolver<dim>::copy_state() const {
  refresh_states(); // the linear explicit path leaves the points behind u
  StateCopy copy;
  copy.displacement = u_;
  copy.velocity = v_;
  copy.committed = committed_;
  copy.active = active_;
  copy.time = time_;
  copy.previous_step = previous_step_;
  copy.loaded = loaded_;
  return copy;
}

template <int dim>
void MechanicsSolver<dim>::restore_state(const StateCopy& copy) {
  // Collective: a rank whose own cells did not change takes the branch with the others.
  if (Utilities::MPI::logical_or(copy.active != active_, comm_))
    set_active_cells(copy.active);
  u_ = copy.displacement;
  v_ = copy.velocity;
  committed_ = trial_ = copy.committed;
  states_stale_ = false;
  time_ = previous_time_ = target_time_ = copy.time;
  previous_step_ = copy.previous_step;
  loaded_ = copy.loaded;
  relax_acceleration_.clear();
  update_ghosts();
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template void MechanicsSolver<dim>::prepare_for_serialization(const std::string&) const;         \
  template void MechanicsSolver<dim>::save_checkpoint(const std::string&) const;                   \
  template void MechanicsSolver<dim>::deserialize(const std::string&);                             \
  template void MechanicsSolver<dim>::load_checkpoint(const std::string&);                         \
  template typename MechanicsSolver<dim>::StateCopy MechanicsSolver<dim>::copy_state() const;      \
  template void MechanicsSolver<dim>::restore_state(const StateCopy&);
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
