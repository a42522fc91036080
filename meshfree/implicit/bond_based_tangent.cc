#include "meshfree/implicit/bond_based_tangent.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <deal.II/base/index_set.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
void BondBasedTangent<dim>::reinit(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  if (bonds.n_particles() != particles.size())
    throw InvalidInput("BondBasedTangent", "bond list built for another particle set",
                       "bonds from NeighborSearch::build on these particles");
  n_particles_ = particles.size();
  n_dofs_ = n_particles_ * dim;
  row_offsets_.assign(n_particles_ + 1, 0);
  row_particles_.clear();
  row_particles_.reserve(bonds.n_bonds() + n_particles_);
  self_slot_.assign(n_particles_, 0);
  bond_slot_.assign(bonds.n_bonds(), -1);

  // Intact neighbours of i plus i itself, sorted: bonds are sorted by neighbour already, but
  // do not rely on it (a sort of ~200 entries costs nothing next to the assembly).
  std::vector<std::pair<unsigned int, std::size_t>> row;
  for (unsigned int i = 0; i < n_particles_; ++i) {
    row.clear();
    row.emplace_back(i, static_cast<std::size_t>(-1));
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (!bonds.broken[k])
        row.emplace_back(j, k);
    });
    std::sort(row.begin(), row.end());
    const std::size_t start = row_particles_.size();
    for (std::size_t s = 0; s < row.size(); ++s) {
      row_particles_.push_back(row[s].first);
      if (row[s].second == static_cast<std::size_t>(-1))
        self_slot_[i] = static_cast<unsigned int>(s);
      else
        bond_slot_[row[s].second] = static_cast<int>(s);
    }
    row_offsets_[i + 1] = start + row.size();
  }

  dealii::DynamicSparsityPattern dsp(n_dofs_, n_dofs_);
  std::vector<dealii::types::global_dof_index> cols;
  for (unsigned int i = 0; i < n_particles_; ++i) {
    cols.clear();
    for (std::size_t s = row_offsets_[i]; s < row_offsets_[i + 1]; ++s)
      for (unsigned int d = 0; d < dim; ++d)
        cols.push_back(dof(row_particles_[s], d));
    for (unsigned int c = 0; c < dim; ++c)
      dsp.add_entries(dof(i, c), cols.begin(), cols.end(), true);
  }
  matrix_.clear();
  matrix_.reinit(dsp);
  constrained_.assign(n_dofs_, 0);
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

  // Pass 1: values per particle row into a flat buffer (parallel; each particle writes only
  // its own rows), the diagonal for the scaling of the constrained rows.
  std::vector<double> values((row_offsets_.back()) * dim * dim);
  std::vector<double> diag(n_dofs_, 0.0);
  for_each_particle(bonds, [&](unsigned int i) {
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

  // Constrained and isolated components; the scale of their diagonal.
  double sum = 0, maxd = 0;
  unsigned int n_free = 0;
  for (unsigned int i = 0; i < n_particles_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!particles.is_fixed(i, d)) {
        sum += diag[dof(i, d)];
        maxd = std::max(maxd, diag[dof(i, d)]);
        ++n_free;
      }
  constrained_diagonal_ = n_free > 0 && sum > 0 ? sum / n_free : 1.0;
  n_isolated_ = 0;
  for (unsigned int i = 0; i < n_particles_; ++i)
    for (unsigned int d = 0; d < dim; ++d) {
      const unsigned int q = dof(i, d);
      constrained_[q] = particles.is_fixed(i, d) ? 1 : 0;
      // A free component with (numerically) no stiffness: every bond broken, or the
      // remaining bonds all perpendicular to it. Pinning it keeps K positive definite.
      if (!constrained_[q] && !(diag[q] > 1e-10 * maxd)) {
        constrained_[q] = 1;
        ++n_isolated_;
      }
      if (!std::isfinite(diag[q])) {
        std::ostringstream where;
        where << "particle " << i << " at (" << particles.reference_position(i) << ")";
        throw NumericalFailure("non-finite tangent stiffness", where.str(),
                               "two particles may coincide (zero bond length)");
      }
    }

  // Pass 2: zero constrained rows and columns, write rows into the matrix.
  std::vector<dealii::types::global_dof_index> cols;
  for (unsigned int i = 0; i < n_particles_; ++i) {
    const std::size_t row_begin = row_offsets_[i];
    const std::size_t n_slots = row_offsets_[i + 1] - row_begin;
    const std::size_t width = n_slots * dim;
    double* rows = values.data() + row_begin * dim * dim;
    cols.resize(width);
    for (std::size_t s = 0; s < n_slots; ++s)
      for (unsigned int d = 0; d < dim; ++d)
        cols[s * dim + d] = dof(row_particles_[row_begin + s], d);
    for (unsigned int r = 0; r < dim; ++r) {
      const unsigned int q = dof(i, r);
      double* row = rows + r * width;
      if (constrained_[q]) {
        std::fill(row, row + width, 0.0);
        row[self_slot_[i] * dim + r] = constrained_diagonal_;
      } else {
        for (std::size_t c = 0; c < width; ++c)
          if (constrained_[cols[c]])
            row[c] = 0.0;
      }
      matrix_.set(q, width, cols.data(), row, false);
    }
  }
  matrix_.compress(dealii::VectorOperation::insert);
}

template <int dim>
void BondBasedTangent<dim>::initialize_vector(VectorType& v) const {
  v.reinit(dealii::complete_index_set(n_dofs_), MPI_COMM_SELF);
}

template <int dim>
void BondBasedTangent<dim>::zero_constrained(VectorType& v) const {
  for (unsigned int q = 0; q < n_dofs_; ++q)
    if (constrained_[q])
      v[q] = 0.0;
  v.compress(dealii::VectorOperation::insert);
}

template <int dim>
std::vector<double>
BondBasedTangent<dim>::particle_stiffness(const ParticleSet<dim>& particles) const {
  std::vector<double> s(n_particles_, 0.0);
  for (unsigned int i = 0; i < n_particles_; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      s[i] += matrix_.el(dof(i, d), dof(i, d));
  return s;
}

template class BondBasedTangent<2>;
template class BondBasedTangent<3>;

} // namespace spinesim::meshfree
