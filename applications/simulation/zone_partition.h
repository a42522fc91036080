#ifndef SPINESIM_APPLICATIONS_SIMULATION_ZONE_PARTITION_H
#define SPINESIM_APPLICATIONS_SIMULATION_ZONE_PARTITION_H

// A particle zone's lattice spread over the ranks of a run (docs/scaling.md). The zone box is
// covered by background cells no smaller than a ghost reach; p4est (through deal.II's
// parallel::distributed::Triangulation) partitions those cells, each weighted by its particles
// (the weight signal), and every lattice point lives on the rank that owns its cell. A rank holds
// its owned points and, as ghosts, the points of its ghost cells: every point within the ghost
// reach of an owned one. Nothing is sized by the global particle count.
//
// Ghost values travel through Trilinos vectors whose index sets are the lattice ids (the
// Epetra import of deal.II's ghosted TrilinosWrappers::MPI::Vector), so the pattern is the
// library's, computed once: the particles of a PD zone never change owner (Lagrangian bonds).

#include "meshfree/bond_list.h"
#include "meshfree/fragments.h"
#include "meshfree/particle_numbering.h"

#include <deal.II/base/index_set.h>
#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/lac/trilinos_vector.h>

#include <mpi.h>

class Epetra_Import;

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace spinesim::applications {

template <int dim>
class ZonePartition {
 public:
  // The cell-centred lattice of meshfree::ParticleSet::lattice on [lo, hi] with spacing h,
  // restricted to the points `keep` accepts. Background cells are at least `ghost_reach` wide.
  ZonePartition(MPI_Comm comm, const dealii::Point<dim>& lo, const dealii::Point<dim>& hi,
                double spacing, double ghost_reach,
                const std::function<bool(const dealii::Point<dim>&)>& keep);
  ~ZonePartition();

  MPI_Comm comm() const { return comm_; }
  // This rank's points: the owned ones first, then the ghosts, each in ascending lattice id
  // (x fastest), with their lattice ids.
  const std::vector<dealii::Point<dim>>& points() const { return points_; }
  const std::vector<std::uint64_t>& ids() const { return ids_; }
  unsigned int n_owned() const { return n_owned_; }
  bool is_owned(unsigned int i) const { return i < n_owned_; }
  double lattice_cell_volume() const { return cell_volume_; } // per unit thickness in 2-D
  std::uint64_t n_global_points() const { return n_global_; }
  unsigned int n_background_cells() const;
  // Owned particles of the busiest rank over the mean: after the weighted partition, and as the
  // equal-cell partition would have had it.
  double load_imbalance() const { return imbalance_; }
  double load_imbalance_unweighted() const { return imbalance_unweighted_; }

  // Keeps the ghosts g with keep[g] (g = 0 for the first ghost), in order, and shrinks the
  // exchange to them. Returns each point's new index (~0u for a dropped ghost). Collective.
  std::vector<unsigned int> keep_ghosts(const std::vector<std::uint8_t>& keep);

  // Copies the owned entries to the ghosts (collective). Sizes: points().size().
  void update_ghosts(std::vector<dealii::Tensor<1, dim>>& values) const;
  void update_ghosts(std::vector<double>& values) const;

  // The points' numbering for the meshfree solvers that work on it (owned first, lattice ids).
  meshfree::ParticleNumbering numbering() const;

  // Bytes this rank holds for the partition (points, ids, exchange vectors).
  std::size_t memory_bytes() const;

 private:
  MPI_Comm comm_;
  std::unique_ptr<dealii::parallel::distributed::Triangulation<dim>> background_;
  std::vector<dealii::Point<dim>> points_;
  std::vector<std::uint64_t> ids_;
  unsigned int n_owned_ = 0;
  double cell_volume_ = 0;
  std::uint64_t n_global_ = 0;
  double imbalance_ = 1, imbalance_unweighted_ = 1;
  // Per-component (id·dim + d) and scalar (id) vectors: owned, and owned + ghosts.
  // Scratch of update_ghosts (const: it changes no state of the partition).
  mutable dealii::TrilinosWrappers::MPI::Vector owned_vector_, ghosted_vector_;
  mutable dealii::TrilinosWrappers::MPI::Vector owned_scalar_, ghosted_scalar_;
  // Where ghost g's first entry sits in the ghosted vectors' local storage.
  std::vector<unsigned int> ghost_vector_slot_, ghost_scalar_slot_;
  // The import plans, made once: an assignment between deal.II vectors of different maps
  // builds a new Epetra_Import every time (measured: a tenth of a step of the weak-scaling
  // block went to its map lookups and sorts).
  std::unique_ptr<Epetra_Import> vector_import_, scalar_import_;
  // (Re)builds the ghosted vectors, import plans and slots for the current points.
  void build_ghosted_vectors();
};

// The fragments of a zone whose bond rows are those of the owned particles of `partition`
// (ghost rows empty; the same counts as meshfree::count_fragments on the whole zone).
// Collective: the components are found by propagating the least lattice id along intact bonds,
// with a ghost exchange per sweep, until no label changes on any rank.
template <int dim>
meshfree::FragmentCount distributed_fragments(const meshfree::BondList<dim>& bonds,
                                              const ZonePartition<dim>& partition);

} // namespace spinesim::applications

#endif
