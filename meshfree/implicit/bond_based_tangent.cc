#include "meshfree/implicit/bond_based_tangent.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <Epetra_CrsMatrix.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
void BondBasedTangent<dim>::reinit(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                   const ParticleNumbering& numbering) {
  if (bonds.n_particles() != particles.size())
    throw InvalidInput("BondBasedTangent", "bond list built for another particle set",
                       "bonds from NeighborSearch::build on these particles");
  numbering_ = numbering;
  ++pattern_generation_;
  n_particles_ = particles.size();
  n_owned_ = std::min(numbering.n_owned, n_particles_);
  if (numbering.distributed()) {
    if (numbering.global_ids.size() != n_particles_)
      throw InvalidInput("BondBasedTangent", "a numbering of another particle set",
                         "one global id per particle of this rank");
    for (unsigned int i = n_owned_; i < n_particles_; ++i)
      if (bonds.end(i) != bonds.begin(i))
        throw InvalidInput("BondBasedTangent", "bond rows of ghost particles",
                           "rows for the owned particles only (BondList::keep_rows)");
  }
  const std::uint64_t n_global =
      numbering.n_global > 0 ? numbering.n_global
                             : dealii::Utilities::MPI::sum(std::uint64_t(n_owned_), numbering.comm);
  n_dofs_ = n_global * dim;
  row_offsets_.assign(n_particles_ + 1, 0);
  row_particles_.clear();
  row_particles_.reserve(bonds.n_bonds() + n_owned_);
  self_slot_.assign(n_particles_, 0);
  bond_slot_.assign(bonds.n_bonds(), -1);

  // Intact neighbours of i plus i itself, sorted: bonds are sorted by neighbour already, but
  // do not rely on it (a sort of ~200 entries costs nothing next to the assembly).
  std::vector<std::pair<unsigned int, std::size_t>> row;
  std::vector<unsigned int> ghosts;
  for (unsigned int i = 0; i < n_particles_; ++i) {
    const std::size_t start = row_particles_.size();
    row_offsets_[i + 1] = start;
    if (i >= n_owned_)
      continue;
    row.clear();
    row.emplace_back(i, static_cast<std::size_t>(-1));
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (!bonds.broken[k])
        row.emplace_back(j, k);
    });
    std::sort(row.begin(), row.end());
    for (std::size_t s = 0; s < row.size(); ++s) {
      row_particles_.push_back(row[s].first);
      if (row[s].first >= n_owned_)
        ghosts.push_back(row[s].first);
      if (row[s].second == static_cast<std::size_t>(-1))
        self_slot_[i] = static_cast<unsigned int>(s);
      else
        bond_slot_[row[s].second] = static_cast<int>(s);
    }
    row_offsets_[i + 1] = start + row.size();
  }
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  bonded_ghosts_ = ghosts;

  owned_dofs_ = dealii::IndexSet(n_dofs_);
  ghost_dofs_ = dealii::IndexSet(n_dofs_);
  owned_dof_order_.clear();
  std::vector<std::pair<std::uint64_t, unsigned int>> by_id;
  by_id.reserve(n_owned_);
  for (unsigned int i = 0; i < n_owned_; ++i)
    by_id.emplace_back(numbering_.id(i), i);
  std::sort(by_id.begin(), by_id.end());
  for (const auto& [id, i] : by_id)
    for (unsigned int d = 0; d < dim; ++d) {
      owned_dofs_.add_index(id * dim + d);
      owned_dof_order_.emplace_back(i, d);
    }
  owned_dofs_.compress();
  for (unsigned int g : bonded_ghosts_)
    for (unsigned int d = 0; d < dim; ++d)
      ghost_dofs_.add_index(global_dof(g, d));
  ghost_dofs_.compress();

  dealii::DynamicSparsityPattern dsp(n_dofs_, n_dofs_, owned_dofs_);
  std::vector<dealii::types::global_dof_index> cols;
  for (unsigned int i = 0; i < n_owned_; ++i) {
    cols.clear();
    for (std::size_t s = row_offsets_[i]; s < row_offsets_[i + 1]; ++s)
      for (unsigned int d = 0; d < dim; ++d)
        cols.push_back(global_dof(row_particles_[s], d));
    std::sort(cols.begin(), cols.end()); // global ids need not follow the local order
    for (unsigned int c = 0; c < dim; ++c)
      dsp.add_entries(global_dof(i, c), cols.begin(), cols.end(), true);
  }
  matrix_.clear();
  matrix_.reinit(owned_dofs_, owned_dofs_, dsp, numbering_.comm);
  constrained_.assign(n_particles_ * dim, 0);

  // Each buffer entry's position in its Epetra row (local column ids through the column map).
  const Epetra_CrsMatrix& epetra = matrix_.trilinos_matrix();
  entry_position_.assign(row_offsets_.back() * dim * dim, 0);
  std::vector<std::pair<int, unsigned int>> stored; // (local column, position), by column
  for (unsigned int i = 0; i < n_owned_; ++i) {
    const std::size_t row_begin = row_offsets_[i];
    const std::size_t width = (row_offsets_[i + 1] - row_begin) * dim;
    for (unsigned int r = 0; r < dim; ++r) {
      int n = 0;
      double* v = nullptr;
      int* columns = nullptr;
      const int local_row =
          epetra.LRID(static_cast<dealii::TrilinosWrappers::types::int_type>(global_dof(i, r)));
      if (local_row < 0 || epetra.ExtractMyRowView(local_row, n, v, columns) != 0 ||
          static_cast<std::size_t>(n) != width)
        throw NumericalFailure("tangent row " + std::to_string(global_dof(i, r)) + " has " +
                                   std::to_string(n) + " stored entries, expected " +
                                   std::to_string(width),
                               "BondBasedTangent::reinit", "an inconsistent sparsity pattern");
      stored.resize(n);
      for (int e = 0; e < n; ++e)
        stored[e] = {columns[e], static_cast<unsigned int>(e)};
      std::sort(stored.begin(), stored.end());
      unsigned int* position = entry_position_.data() + row_begin * dim * dim + r * width;
      for (std::size_t s = 0; s < width / dim; ++s)
        for (unsigned int c = 0; c < dim; ++c) {
          const int lcid = epetra.LCID(static_cast<dealii::TrilinosWrappers::types::int_type>(
              global_dof(row_particles_[row_begin + s], c)));
          const auto it = std::lower_bound(stored.begin(), stored.end(),
                                           std::pair<int, unsigned int>(lcid, 0u));
          if (lcid < 0 || it == stored.end() || it->first != lcid)
            throw NumericalFailure("tangent column missing from the sparsity pattern",
                                   "BondBasedTangent::reinit", "an inconsistent sparsity pattern");
          position[s * dim + c] = it->second;
        }
    }
  }
}

template <int dim>
void BondBasedTangent<dim>::assemble(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                     const BondBasedPD<dim>& model, bool geometric) {
  using Vec = dealii::Tensor<1, dim>;
  if (particles.size() != n_particles_ || bonds.n_bonds() != bond_slot_.size())
    throw InvalidInput("BondBasedTangent::assemble", "called before reinit on these bonds",
                       "reinit(particles, bonds) first");
  const std::vector<double>& kb = model.bond_stiffness();
  if (kb.size() != bonds.n_bonds())
    throw InvalidInput("BondBasedTangent::assemble", "model not initialised on these bonds",
                       "BondBasedPD::initialise(particles, bonds) first");
  const Vec* u = particles.displacements().data();
  const double* V = particles.volumes().data();
  const MPI_Comm comm = numbering_.comm;

  // Pass 1: values per owned particle row into a flat buffer (parallel; each particle writes
  // only its own rows), the diagonal for the scaling of the constrained rows.
  std::vector<double> values((row_offsets_.back()) * dim * dim);
  std::vector<double> diag(n_particles_ * dim, 0.0);
  for_each_particle(bonds, [&](unsigned int i) {
    if (i >= n_owned_)
      return;
    const std::size_t row_begin = row_offsets_[i];
    const std::size_t width = (row_offsets_[i + 1] - row_begin) * dim;
    double* rows = values.data() + row_begin * dim * dim; // dim rows of `width` entries
    std::fill(rows, rows + dim * width, 0.0);
    dealii::Tensor<2, dim> self;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (bonds.broken[k] || bond_slot_[k] < 0)
        return;
      const Vec y = bonds.xi[k] + (u[j] - u[i]);
      const double l = y.norm();
      const Vec n = y / l;
      const double a = V[i] * kb[k];
      const double g = geometric ? (l - bonds.length[k]) / l : 0.0;
      dealii::Tensor<2, dim> B;
      for (unsigned int r = 0; r < dim; ++r)
        for (unsigned int c = 0; c < dim; ++c)
          B[r][c] = a * ((1.0 - g) * n[r] * n[c] + (r == c ? g : 0.0));
      self += B;
      const std::size_t slot = static_cast<std::size_t>(bond_slot_[k]);
      for (unsigned int r = 0; r < dim; ++r)
        for (unsigned int c = 0; c < dim; ++c)
          rows[r * width + slot * dim + c] = -B[r][c];
    });
    const std::size_t s = self_slot_[i];
    for (unsigned int r = 0; r < dim; ++r) {
      for (unsigned int c = 0; c < dim; ++c)
        rows[r * width + s * dim + c] = self[r][c];
      diag[dof(i, r)] = self[r][r];
    }
  });

  // Constrained and isolated components; the scale of their diagonal (over all ranks).
  double sums[2] = {0, 0}, maxd = 0;
  for (unsigned int i = 0; i < n_owned_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!particles.is_fixed(i, d)) {
        sums[0] += diag[dof(i, d)];
        maxd = std::max(maxd, diag[dof(i, d)]);
        sums[1] += 1;
      }
  if (numbering_.distributed()) {
    const double local[2] = {sums[0], sums[1]};
    dealii::Utilities::MPI::sum(dealii::ArrayView<const double>(local, 2), comm,
                                dealii::ArrayView<double>(sums, 2));
    maxd = dealii::Utilities::MPI::max(maxd, comm);
  }
  constrained_diagonal_ = sums[1] > 0 && sums[0] > 0 ? sums[0] / sums[1] : 1.0;
  unsigned int isolated = 0;
  std::string non_finite;
  for (unsigned int i = 0; i < n_particles_; ++i)
    for (unsigned int d = 0; d < dim; ++d) {
      const unsigned int q = dof(i, d);
      constrained_[q] = particles.is_fixed(i, d) ? 1 : 0;
      if (i >= n_owned_)
        continue; // a ghost's owner decides whether it is isolated (below)
      // A free component with (numerically) no stiffness: every bond broken, or the
      // remaining bonds all perpendicular to it. Pinning it keeps K positive definite.
      if (!constrained_[q] && !(diag[q] > 1e-10 * maxd)) {
        constrained_[q] = 1;
        ++isolated;
      }
      if (!std::isfinite(diag[q]) && non_finite.empty()) {
        std::ostringstream where;
        where << "particle " << numbering_.id(i) << " at (" << particles.reference_position(i)
              << ")";
        non_finite = where.str();
      }
    }
  if (numbering_.distributed()) {
    // One rank's non-finite row stops every rank alike.
    const unsigned int bad = dealii::Utilities::MPI::max(non_finite.empty() ? 0u : 1u, comm);
    if (bad && non_finite.empty())
      non_finite = "another rank's particle";
    n_isolated_ = dealii::Utilities::MPI::sum(isolated, comm);
    // The ghosts' flags from their owners (an isolated ghost is pinned there).
    VectorType owned(owned_dofs_, comm), ghosted(owned_dofs_, ghost_dofs_, comm);
    for (unsigned int i = 0; i < n_owned_; ++i)
      for (unsigned int d = 0; d < dim; ++d)
        owned[global_dof(i, d)] = constrained_[dof(i, d)];
    owned.compress(dealii::VectorOperation::insert);
    ghosted = owned;
    for (unsigned int g : bonded_ghosts_)
      for (unsigned int d = 0; d < dim; ++d)
        constrained_[dof(g, d)] = ghosted[global_dof(g, d)] != 0.0 ? 1 : 0;
  } else {
    n_isolated_ = isolated;
  }
  if (!non_finite.empty())
    throw NumericalFailure("non-finite tangent stiffness", non_finite,
                           "two particles may coincide (zero bond length)");

  // Pass 2: zero constrained rows and columns, write rows into the matrix.
  const Epetra_CrsMatrix& epetra = matrix_.trilinos_matrix();
  std::vector<unsigned int> local_cols;
  for (unsigned int i = 0; i < n_owned_; ++i) {
    const std::size_t row_begin = row_offsets_[i];
    const std::size_t n_slots = row_offsets_[i + 1] - row_begin;
    const std::size_t width = n_slots * dim;
    double* rows = values.data() + row_begin * dim * dim;
    local_cols.resize(width);
    for (std::size_t s = 0; s < n_slots; ++s)
      for (unsigned int d = 0; d < dim; ++d)
        local_cols[s * dim + d] = dof(row_particles_[row_begin + s], d);
    for (unsigned int r = 0; r < dim; ++r) {
      const unsigned int q = dof(i, r);
      double* row = rows + r * width;
      if (constrained_[q]) {
        std::fill(row, row + width, 0.0);
        row[self_slot_[i] * dim + r] = constrained_diagonal_;
      } else {
        for (std::size_t c = 0; c < width; ++c)
          if (constrained_[local_cols[c]])
            row[c] = 0.0;
      }
      // In place (entry_position_): the pattern holds exactly these columns.
      int n = 0;
      double* stored = nullptr;
      int* columns = nullptr;
      epetra.ExtractMyRowView(
          epetra.LRID(static_cast<dealii::TrilinosWrappers::types::int_type>(global_dof(i, r))), n,
          stored, columns);
      const unsigned int* position = entry_position_.data() + row_begin * dim * dim + r * width;
      for (std::size_t c = 0; c < width; ++c)
        stored[position[c]] = row[c];
    }
  }
}

template <int dim>
void BondBasedTangent<dim>::initialize_vector(VectorType& v) const {
  v.reinit(owned_dofs_, numbering_.comm);
}

template <int dim>
void BondBasedTangent<dim>::zero_constrained(VectorType& v) const {
  for (unsigned int i = 0; i < n_owned_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (constrained_[dof(i, d)])
        v[global_dof(i, d)] = 0.0;
  v.compress(dealii::VectorOperation::insert);
}

template <int dim>
std::vector<double>
BondBasedTangent<dim>::particle_stiffness(const ParticleSet<dim>& particles) const {
  (void)particles;
  std::vector<double> s(n_particles_, 0.0);
  for (unsigned int i = 0; i < n_owned_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      s[i] += matrix_.el(global_dof(i, d), global_dof(i, d));
  return s;
}

template class BondBasedTangent<2>;
template class BondBasedTangent<3>;

} // namespace spinesim::meshfree
