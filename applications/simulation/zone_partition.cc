#include "applications/simulation/zone_partition.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>
#include <deal.II/grid/grid_generator.h>

#include <Epetra_FEVector.h>
#include <Epetra_Import.h>
#include <Epetra_MultiVector.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

namespace spinesim::applications {

namespace zone_partition_detail {

// The background cell (per-direction indices) of a point: the same arithmetic on every rank,
// so each lattice point has exactly one owner even on a cell face.
template <int dim>
std::array<unsigned int, dim> cell_of(const dealii::Point<dim>& x, const dealii::Point<dim>& lo,
                                      const std::array<double, dim>& width,
                                      const std::array<unsigned int, dim>& cells) {
  std::array<unsigned int, dim> b;
  for (unsigned int d = 0; d < dim; ++d) {
    const double s = std::floor((x[d] - lo[d]) / width[d]);
    b[d] = s < 0 ? 0u : std::min<unsigned int>(cells[d] - 1, static_cast<unsigned int>(s));
  }
  return b;
}

template <int dim>
std::uint64_t linear(const std::array<unsigned int, dim>& b,
                     const std::array<unsigned int, dim>& cells) {
  std::uint64_t key = 0;
  for (int d = dim - 1; d >= 0; --d)
    key = key * cells[d] + b[d];
  return key;
}

} // namespace zone_partition_detail

template <int dim>
ZonePartition<dim>::ZonePartition(MPI_Comm comm, const dealii::Point<dim>& lo,
                                  const dealii::Point<dim>& hi, double spacing, double ghost_reach,
                                  const std::function<bool(const dealii::Point<dim>&)>& keep)
    : comm_(comm) {
  using namespace zone_partition_detail;
  // The lattice of ParticleSet::lattice: n_d cells of width dx_d, a point at each centre.
  std::array<unsigned int, dim> n;
  std::array<double, dim> dx;
  cell_volume_ = 1;
  n_global_ = 1;
  for (unsigned int d = 0; d < dim; ++d) {
    const double length = hi[d] - lo[d];
    n[d] = static_cast<unsigned int>(std::max<long>(1, std::lround(length / spacing)));
    dx[d] = length / n[d];
    cell_volume_ *= dx[d];
    n_global_ *= n[d];
  }
  if (n_global_ * dim >= (std::uint64_t(1) << 31))
    throw InvalidInput("Particles/Spacing",
                       std::to_string(n_global_) + " lattice points: the ghost exchange indexes " +
                           "dim values per point with 32-bit Trilinos ids",
                       "fewer than 2^31 / dim lattice points in the Particles box");

  // Background cells at least ghost_reach wide, all of them coarse cells (p4est trees).
  // Refined cells would be coarser to partition: p4est keeps the 2^dim children of a cell on
  // one rank (partitioning for coarsening), so a block refined once could not be split at
  // all. deal.II orders the trees by Cuthill-McKee, which the partition follows.
  std::vector<unsigned int> coarse(dim);
  std::array<unsigned int, dim> cells;
  std::array<double, dim> width;
  for (unsigned int d = 0; d < dim; ++d) {
    cells[d] = std::max(1u, static_cast<unsigned int>(std::floor((hi[d] - lo[d]) / ghost_reach)));
    coarse[d] = cells[d];
    width[d] = (hi[d] - lo[d]) / cells[d]; // >= ghost_reach
  }
  background_ = std::make_unique<dealii::parallel::distributed::Triangulation<dim>>(comm);
  dealii::GridGenerator::subdivided_hyper_rectangle(*background_, coarse, lo, hi);

  // Calls f(id, x) for the lattice points of background cell b inside the body, each for its
  // own cell only.
  const auto for_each_point = [&](const std::array<unsigned int, dim>& b, auto&& f) {
    std::array<unsigned int, dim> k_lo, k_hi;
    for (unsigned int d = 0; d < dim; ++d) {
      const double first = std::floor(b[d] * width[d] / dx[d]) - 1;
      const double last = std::ceil((b[d] + 1) * width[d] / dx[d]) + 1;
      k_lo[d] = first < 0 ? 0u : static_cast<unsigned int>(first);
      k_hi[d] = std::min<unsigned int>(n[d] - 1, static_cast<unsigned int>(std::max(0.0, last)));
    }
    const std::uint64_t key = linear<dim>(b, cells);
    std::array<unsigned int, dim> k = k_lo;
    while (true) {
      dealii::Point<dim> x;
      for (unsigned int d = 0; d < dim; ++d)
        x[d] = lo[d] + (k[d] + 0.5) * dx[d]; // ParticleSet::lattice's formula, bit for bit
      if (linear<dim>(cell_of<dim>(x, lo, width, cells), cells) == key && keep(x)) {
        std::uint64_t id = 0;
        for (int d = dim - 1; d >= 0; --d)
          id = id * n[d] + k[d];
        f(id, x);
      }
      unsigned int d = 0;
      while (d < dim && k[d] == k_hi[d]) {
        k[d] = k_lo[d];
        ++d;
      }
      if (d == dim)
        break;
      ++k[d];
    }
  };

  // Weighted partition (deal.II's weight signal, as in step-68): a cell weighs its particles,
  // so a shape that leaves cells empty (a ring in its box) does not leave ranks idle. The
  // first call counts this rank's particles under the equal-cell partition.
  double unweighted_load = 0;
  const auto connection = background_->signals.weight.connect(
      [&](const typename dealii::Triangulation<dim>::cell_iterator& cell,
          const typename dealii::Triangulation<dim>::CellStatus) -> unsigned int {
        unsigned int count = 0;
        for_each_point(cell_of<dim>(cell->center(), lo, width, cells),
                       [&count](std::uint64_t, const dealii::Point<dim>&) { ++count; });
        unweighted_load += count;
        return count;
      });
  background_->repartition();
  connection.disconnect();
  imbalance_unweighted_ = dealii::Utilities::MPI::max(unweighted_load, comm) /
                          std::max(1.0, dealii::Utilities::MPI::sum(unweighted_load, comm) /
                                            dealii::Utilities::MPI::n_mpi_processes(comm));

  // This rank's points: those of its owned cells, and of its ghost cells as ghosts.
  std::vector<std::pair<std::uint64_t, dealii::Point<dim>>> owned, ghosts;
  for (const auto& cell : background_->active_cell_iterators()) {
    if (!cell->is_locally_owned() && !cell->is_ghost())
      continue;
    auto& list = cell->is_locally_owned() ? owned : ghosts;
    for_each_point(
        cell_of<dim>(cell->center(), lo, width, cells),
        [&list](std::uint64_t id, const dealii::Point<dim>& x) { list.emplace_back(id, x); });
  }
  const auto by_id = [](const auto& a, const auto& b) { return a.first < b.first; };
  std::sort(owned.begin(), owned.end(), by_id);
  std::sort(ghosts.begin(), ghosts.end(), by_id);
  n_owned_ = owned.size();
  imbalance_ = dealii::Utilities::MPI::max(double(n_owned_), comm) /
               std::max(1.0, dealii::Utilities::MPI::sum(double(n_owned_), comm) /
                                 dealii::Utilities::MPI::n_mpi_processes(comm));
  for (const auto* list : {&owned, &ghosts})
    for (const auto& [id, x] : *list) {
      ids_.push_back(id);
      points_.push_back(x);
    }

  // Exchange vectors over lattice ids.
  dealii::IndexSet owned_dofs(n_global_ * dim), owned_ids(n_global_);
  for (unsigned int i = 0; i < n_owned_; ++i) {
    for (unsigned int d = 0; d < dim; ++d)
      owned_dofs.add_index(ids_[i] * dim + d);
    owned_ids.add_index(ids_[i]);
  }
  owned_dofs.compress();
  owned_ids.compress();
  owned_vector_.reinit(owned_dofs, comm);
  owned_scalar_.reinit(owned_ids, comm);
  build_ghosted_vectors();
}

template <int dim>
void ZonePartition<dim>::build_ghosted_vectors() {
  dealii::IndexSet relevant_dofs(n_global_ * dim), relevant_ids(n_global_);
  for (unsigned int i = 0; i < ids_.size(); ++i) {
    for (unsigned int d = 0; d < dim; ++d)
      relevant_dofs.add_index(ids_[i] * dim + d);
    relevant_ids.add_index(ids_[i]);
  }
  relevant_dofs.compress();
  relevant_ids.compress();
  ghosted_vector_.reinit(owned_vector_.locally_owned_elements(), relevant_dofs, comm_);
  ghosted_scalar_.reinit(owned_scalar_.locally_owned_elements(), relevant_ids, comm_);
  vector_import_ = std::make_unique<Epetra_Import>(ghosted_vector_.trilinos_vector().Map(),
                                                   owned_vector_.trilinos_vector().Map());
  scalar_import_ = std::make_unique<Epetra_Import>(ghosted_scalar_.trilinos_vector().Map(),
                                                   owned_scalar_.trilinos_vector().Map());
  ghost_vector_slot_.clear();
  ghost_scalar_slot_.clear();
  for (unsigned int i = n_owned_; i < ids_.size(); ++i) {
    ghost_vector_slot_.push_back(relevant_dofs.index_within_set(ids_[i] * dim));
    ghost_scalar_slot_.push_back(relevant_ids.index_within_set(ids_[i]));
  }
}

template <int dim>
std::vector<unsigned int> ZonePartition<dim>::keep_ghosts(const std::vector<std::uint8_t>& keep) {
  AssertDimension(keep.size(), points_.size() - n_owned_);
  std::vector<unsigned int> new_index(points_.size(), ~0u);
  unsigned int next = n_owned_;
  for (unsigned int i = 0; i < n_owned_; ++i)
    new_index[i] = i;
  for (unsigned int g = 0; g < keep.size(); ++g)
    if (keep[g]) {
      points_[next] = points_[n_owned_ + g];
      ids_[next] = ids_[n_owned_ + g];
      new_index[n_owned_ + g] = next++;
    }
  points_.resize(next);
  ids_.resize(next);
  points_.shrink_to_fit();
  ids_.shrink_to_fit();
  build_ghosted_vectors();
  return new_index;
}

template <int dim>
ZonePartition<dim>::~ZonePartition() = default;

template <int dim>
unsigned int ZonePartition<dim>::n_background_cells() const {
  return background_->n_global_active_cells();
}

template <int dim>
void ZonePartition<dim>::update_ghosts(std::vector<dealii::Tensor<1, dim>>& values) const {
  AssertDimension(values.size(), points_.size());
  auto& owned = owned_vector_;
  auto& ghosted = ghosted_vector_;
  // The owned map lists ids ascending and the owned points are sorted by id: local entry
  // i·dim + d is point i's component d.
  double* out = owned.trilinos_vector()[0];
  for (unsigned int i = 0; i < n_owned_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      out[i * dim + d] = values[i][d];
  ghosted.trilinos_vector().Import(owned.trilinos_vector(), *vector_import_, Insert);
  const double* in = ghosted.trilinos_vector()[0];
  for (unsigned int g = 0; g < ghost_vector_slot_.size(); ++g)
    for (unsigned int d = 0; d < dim; ++d)
      values[n_owned_ + g][d] = in[ghost_vector_slot_[g] + d];
}

template <int dim>
void ZonePartition<dim>::update_ghosts(std::vector<double>& values) const {
  AssertDimension(values.size(), points_.size());
  auto& owned = owned_scalar_;
  auto& ghosted = ghosted_scalar_;
  double* out = owned.trilinos_vector()[0];
  for (unsigned int i = 0; i < n_owned_; ++i)
    out[i] = values[i];
  ghosted.trilinos_vector().Import(owned.trilinos_vector(), *scalar_import_, Insert);
  const double* in = ghosted.trilinos_vector()[0];
  for (unsigned int g = 0; g < ghost_scalar_slot_.size(); ++g)
    values[n_owned_ + g] = in[ghost_scalar_slot_[g]];
}

template <int dim>
meshfree::ParticleNumbering ZonePartition<dim>::numbering() const {
  meshfree::ParticleNumbering n;
  n.comm = comm_;
  n.global_ids = ids_;
  n.n_owned = n_owned_;
  n.n_global = n_global_;
  return n;
}

template <int dim>
std::size_t ZonePartition<dim>::memory_bytes() const {
  return points_.capacity() * sizeof(dealii::Point<dim>) + ids_.capacity() * sizeof(std::uint64_t) +
         (ghost_vector_slot_.capacity() + ghost_scalar_slot_.capacity()) * sizeof(unsigned int) +
         owned_vector_.memory_consumption() + ghosted_vector_.memory_consumption() +
         owned_scalar_.memory_consumption() + ghosted_scalar_.memory_consumption();
}

template <int dim>
meshfree::FragmentCount distributed_fragments(const meshfree::BondList<dim>& bonds,
                                              const ZonePartition<dim>& partition) {
  const MPI_Comm comm = partition.comm();
  const unsigned int n = partition.points().size(), n_owned = partition.n_owned();
  const auto& ids = partition.ids();
  // Labels as doubles: lattice ids below 2^31 are exact.
  std::vector<double> label(n);
  for (unsigned int i = 0; i < n; ++i)
    label[i] = double(ids[i]);
  std::vector<std::uint8_t> bonded(n_owned, 0);
  for (unsigned int i = 0; i < n_owned; ++i)
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
      bonded[i] |= !bonds.broken[k];
  while (true) {
    bool changed = false, sweep_changed = true;
    while (sweep_changed) {
      sweep_changed = false;
      for (unsigned int i = 0; i < n_owned; ++i)
        for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
          if (!bonds.broken[k] && label[bonds.neighbor[k]] < label[i]) {
            label[i] = label[bonds.neighbor[k]];
            sweep_changed = true;
          }
      changed = changed || sweep_changed;
    }
    partition.update_ghosts(label);
    if (!dealii::Utilities::MPI::logical_or(changed, comm))
      break;
  }
  // A component's root is its particle of least id; its size is summed on the root's owner.
  meshfree::FragmentCount count;
  std::map<std::uint64_t, unsigned int> members; // label -> owned bonded particles here
  for (unsigned int i = 0; i < n_owned; ++i) {
    if (!bonded[i]) {
      ++count.isolated;
      continue;
    }
    const auto root = static_cast<std::uint64_t>(label[i]);
    count.fragments += root == ids[i];
    ++members[root];
  }
  dealii::IndexSet owned_ids(partition.n_global_points()), roots(partition.n_global_points());
  for (unsigned int i = 0; i < n_owned; ++i)
    owned_ids.add_index(ids[i]);
  for (const auto& [root, c] : members)
    roots.add_index(root);
  owned_ids.compress();
  roots.compress();
  const std::vector<unsigned int> owners =
      dealii::Utilities::MPI::compute_index_owner(owned_ids, roots, comm);
  std::map<unsigned int, std::vector<std::pair<std::uint64_t, unsigned int>>> send;
  unsigned int r = 0;
  for (const auto& [root, c] : members) // ascending, as the IndexSet lists them
    send[owners[r++]].emplace_back(root, c);
  std::map<std::uint64_t, unsigned int> size;
  for (const auto& [from, list] : dealii::Utilities::MPI::some_to_some(comm, send))
    for (const auto& [root, c] : list)
      size[root] += c;
  unsigned int largest = count.isolated > 0 ? 1 : 0; // an isolated particle is a piece of 1
  for (const auto& [root, s] : size)
    largest = std::max(largest, s);
  count.fragments = dealii::Utilities::MPI::sum(count.fragments, comm);
  count.isolated = dealii::Utilities::MPI::sum(count.isolated, comm);
  count.largest = dealii::Utilities::MPI::max(largest, comm);
  return count;
}

template class ZonePartition<2>;
template class ZonePartition<3>;
template meshfree::FragmentCount distributed_fragments(const meshfree::BondList<2>&,
                                                       const ZonePartition<2>&);
template meshfree::FragmentCount distributed_fragments(const meshfree::BondList<3>&,
                                                       const ZonePartition<3>&);

} // namespace spinesim::applications
