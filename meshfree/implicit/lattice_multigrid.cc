#include "meshfree/implicit/lattice_multigrid.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"
#include "meshfree/implicit/block_csr_matrix.h"
#include "meshfree/neighbor_search.h"

#include <deal.II/base/index_set.h>
#include <deal.II/lac/diagonal_matrix.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>

#include <array>
#include <chrono>
#include <cmath>
#include <string>

namespace spinesim::meshfree {

template <int dim>
struct LatticeMultigrid<dim>::Level {
  double h = 0;
  unsigned int n[dim] = {};
  std::size_t n_particles = 0;
  std::vector<std::uint8_t> constrained; // per dof
  std::vector<dealii::Point<dim>> positions;
  const dealii::TrilinosWrappers::SparseMatrix* matrix = nullptr;
  // Coarse levels own their discretisation.
  std::unique_ptr<ParticleSet<dim>> particles;
  std::unique_ptr<BondList<dim>> bonds;
  std::unique_ptr<BondBasedPD<dim>> model;
  std::unique_ptr<BondBasedTangent<dim>> tangent;
  // From this level to the next finer one (rows: finer dofs, columns: this level's dofs).
  dealii::TrilinosWrappers::SparseMatrix prolongation;
  BlockCsrMatrix<dim> fast; // single-precision copy of *matrix for the smoother
  std::vector<double> inverse_diagonal;
  double lambda_max = 0; // of D⁻¹K
  mutable VectorType x, b, r, tmp;
};

template <int dim>
LatticeMultigrid<dim>::LatticeMultigrid(const Geometry& geometry, const Options& options)
    : geometry_(geometry), options_(options) {
  if (!(geometry_.spacing > 0.0))
    throw InvalidInput("LatticeMultigrid", "lattice spacing <= 0", "the spacing h > 0 [m]");
}

template <int dim>
LatticeMultigrid<dim>::~LatticeMultigrid() = default;

template <int dim>
unsigned int LatticeMultigrid<dim>::n_dofs(unsigned int level) const {
  return static_cast<unsigned int>(levels_.at(level)->n_particles * dim);
}

template <int dim>
void LatticeMultigrid<dim>::initialize(const BondBasedTangent<dim>& fine,
                                       const ParticleSet<dim>& fine_particles) {
  timings_ = Timings();
  const auto t0 = std::chrono::steady_clock::now();
  if (!coarse_built_) {
    levels_.clear();
    auto level = std::make_unique<Level>();
    level->h = geometry_.spacing;
    std::size_t total = 1;
    for (unsigned int d = 0; d < dim; ++d) {
      level->n[d] = static_cast<unsigned int>(
          std::max<long>(1, std::lround((geometry_.hi[d] - geometry_.lo[d]) / level->h)));
      total *= level->n[d];
    }
    if (total != fine_particles.size())
      throw InvalidInput("multigrid", "the particles are not the lattice of the Geometry",
                         "particles from ParticleSet::lattice(lo, hi, h)");
    level->n_particles = total;
    level->positions = fine_particles.reference_positions();
    level->constrained.resize(total * dim);
    for (unsigned int q = 0; q < total * dim; ++q)
      level->constrained[q] = fine.is_constrained(q);
    levels_.push_back(std::move(level));
    build_coarse_levels(fine_particles);
    coarse_built_ = true;
  }
  timings_.coarse_levels = seconds_since(t0);
  levels_[0]->matrix = &fine.matrix();
  for (auto& level : levels_) {
    level->x.reinit(dealii::complete_index_set(level->n_particles * dim), MPI_COMM_SELF);
    level->b.reinit(level->x);
    level->r.reinit(level->x);
    level->tmp.reinit(level->x);
  }
  for (unsigned int l = 0; l + 1 < levels_.size(); ++l) {
    const auto t1 = std::chrono::steady_clock::now();
    levels_[l]->fast.reinit(*levels_[l]->matrix);
    timings_.block_copy += seconds_since(t1);
    const auto t2 = std::chrono::steady_clock::now();
    setup_smoother(*levels_[l]);
    timings_.eigenvalues += seconds_since(t2);
  }
  const auto t3 = std::chrono::steady_clock::now();
  coarse_control_ = std::make_unique<dealii::SolverControl>(1, 0);
  coarse_solver_ = std::make_unique<dealii::TrilinosWrappers::SolverDirect>(
      *coarse_control_,
      dealii::TrilinosWrappers::SolverDirect::AdditionalData(false, "Amesos_Klu"));
  coarse_solver_->initialize(*levels_.back()->matrix);
  timings_.coarse_factorisation = seconds_since(t3);
}

template <int dim>
void LatticeMultigrid<dim>::build_coarse_levels(const ParticleSet<dim>& fine_particles) {
  const double delta = geometry_.model.horizon_ratio * geometry_.spacing;
  while (levels_.size() < options_.max_levels) {
    const Level& fine = *levels_.back();
    const double hc = 2.0 * fine.h;
    bool even = true;
    for (unsigned int d = 0; d < dim; ++d)
      even = even && fine.n[d] % 2 == 0 && fine.n[d] >= 4;
    const double Rc = delta / hc;
    if (!even || Rc < options_.min_horizon_ratio - 1e-12)
      break;

    auto level = std::make_unique<Level>();
    level->h = hc;
    for (unsigned int d = 0; d < dim; ++d)
      level->n[d] = fine.n[d] / 2;
    level->particles = std::make_unique<ParticleSet<dim>>(
        ParticleSet<dim>::lattice(geometry_.lo, geometry_.hi, hc, geometry_.thickness));
    ParticleSet<dim>& P = *level->particles;
    level->n_particles = P.size();
    level->positions = P.reference_positions();
    const std::size_t nc = P.size();

    // Lattice index <-> particle index (x fastest, as ParticleSet::lattice orders them).
    auto fine_index = [&](const std::array<unsigned int, dim>& f) {
      std::size_t idx = 0, stride = 1;
      for (unsigned int d = 0; d < dim; ++d) {
        idx += f[d] * stride;
        stride *= fine.n[d];
      }
      return idx;
    };
    auto coarse_multi = [&](std::size_t c) {
      std::array<unsigned int, dim> I;
      for (unsigned int d = 0; d < dim; ++d) {
        I[d] = c % level->n[d];
        c /= level->n[d];
      }
      return I;
    };
    auto coarse_index = [&](const std::array<int, dim>& I) {
      std::size_t idx = 0, stride = 1;
      for (unsigned int d = 0; d < dim; ++d) {
        idx += I[d] * stride;
        stride *= level->n[d];
      }
      return idx;
    };

    // Dirichlet: constrained when every child is.
    level->constrained.assign(nc * dim, 0);
    for (std::size_t c = 0; c < nc; ++c) {
      const auto I = coarse_multi(c);
      for (unsigned int comp = 0; comp < dim; ++comp) {
        bool all = true;
        for (unsigned int child = 0; child < (1u << dim); ++child) {
          std::array<unsigned int, dim> f;
          for (unsigned int d = 0; d < dim; ++d)
            f[d] = 2 * I[d] + ((child >> d) & 1u);
          all = all && fine.constrained[fine_index(f) * dim + comp];
        }
        if (all) {
          P.set_fixed(static_cast<unsigned int>(c), comp);
          level->constrained[c * dim + comp] = 1;
        }
      }
    }

    // Re-discretised operator at u = 0 with the same horizon.
    auto prm = geometry_.model;
    prm.horizon_ratio = delta / hc;
    level->model =
        std::make_unique<BondBasedPD<dim>>(prm, geometry_.youngs_modulus, geometry_.poisson_ratio);
    auto options = level->model->neighbor_options(hc);
    options.horizon = delta;
    options.pre_cracks = geometry_.pre_cracks;
    level->bonds = std::make_unique<BondList<dim>>(NeighborSearch<dim>(options).build(P));
    level->model->initialise(P, *level->bonds);
    level->tangent = std::make_unique<BondBasedTangent<dim>>();
    level->tangent->reinit(P, *level->bonds);
    level->tangent->assemble(P, *level->bonds, *level->model, false);
    level->matrix = &level->tangent->matrix();
    for (unsigned int q = 0; q < nc * dim; ++q)
      level->constrained[q] = level->tangent->is_constrained(q);

    // Prolongation: tensor-product 3/4–1/4 weights, none across a pre-crack.
    const std::size_t nf = fine.n_particles;
    dealii::DynamicSparsityPattern dsp(nf * dim, nc * dim);
    std::vector<std::vector<std::pair<std::size_t, double>>> weights(nf);
    for (std::size_t fi = 0; fi < nf; ++fi) {
      std::array<unsigned int, dim> f;
      std::size_t rest = fi;
      for (unsigned int d = 0; d < dim; ++d) {
        f[d] = rest % fine.n[d];
        rest /= fine.n[d];
      }
      std::array<std::array<int, 2>, dim> idx;
      std::array<std::array<double, 2>, dim> w;
      std::array<unsigned int, dim> count;
      for (unsigned int d = 0; d < dim; ++d) {
        const int I = static_cast<int>(f[d] / 2);
        const int J = (f[d] % 2 == 0) ? I - 1 : I + 1;
        idx[d][0] = I;
        if (J < 0 || J >= static_cast<int>(level->n[d])) {
          w[d][0] = 1.0;
          count[d] = 1;
        } else {
          idx[d][1] = J;
          w[d][0] = 0.75;
          w[d][1] = 0.25;
          count[d] = 2;
        }
      }
      const dealii::Point<dim>& xf = fine.positions[fi];
      double sum = 0;
      std::size_t parent = 0;
      for (unsigned int combo = 0; combo < (1u << dim); ++combo) {
        std::array<int, dim> I;
        double wt = 1;
        bool valid = true;
        for (unsigned int d = 0; d < dim; ++d) {
          const unsigned int s = (combo >> d) & 1u;
          if (s >= count[d]) {
            valid = false;
            break;
          }
          I[d] = idx[d][s];
          wt *= w[d][s];
        }
        if (!valid)
          continue;
        const std::size_t c = coarse_index(I);
        if (combo == 0)
          parent = c;
        bool cut = false;
        for (const auto& crack : geometry_.pre_cracks)
          cut = cut || crack.cuts(xf, level->positions[c]);
        if (cut)
          continue;
        weights[fi].emplace_back(c, wt);
        sum += wt;
      }
      if (weights[fi].empty())
        weights[fi].emplace_back(parent, sum = 1.0);
      for (auto& [c, wt] : weights[fi])
        wt /= sum;
      for (unsigned int comp = 0; comp < dim; ++comp)
        for (const auto& [c, wt] : weights[fi])
          dsp.add(fi * dim + comp, c * dim + comp);
    }
    level->prolongation.reinit(dealii::complete_index_set(nf * dim),
                               dealii::complete_index_set(nc * dim), dsp, MPI_COMM_SELF);
    for (std::size_t fi = 0; fi < nf; ++fi)
      for (unsigned int comp = 0; comp < dim; ++comp) {
        const std::size_t row = fi * dim + comp;
        if (fine.constrained[row])
          continue;
        for (const auto& [c, wt] : weights[fi])
          if (!level->constrained[c * dim + comp])
            level->prolongation.set(row, c * dim + comp, wt);
      }
    level->prolongation.compress(dealii::VectorOperation::insert);
    levels_.push_back(std::move(level));
  }
  (void)fine_particles;
}

template <int dim>
void LatticeMultigrid<dim>::setup_smoother(Level& level) const {
  const std::size_t n = level.n_particles * dim;
  level.inverse_diagonal.resize(n);
  for (std::size_t q = 0; q < n; ++q)
    level.inverse_diagonal[q] = 1.0 / level.fast.diagonal()[q];
  // λmax(D⁻¹K) from the Lanczos matrix of a few Jacobi-PCG steps on the single-precision
  // copy (the operator the smoother applies): the extreme Ritz values converge first (a power
  // iteration needs many more products on large lattices, and an underestimate makes the
  // Chebyshev smoother amplify the top of the spectrum).
  VectorType& rhs = level.tmp;
  VectorType& sol = level.r;
  VectorType inv(rhs);
  for (std::size_t q = 0; q < n; ++q) {
    rhs[q] = 1.0 + 0.5 * std::sin(1.3 * q);
    inv[q] = level.inverse_diagonal[q];
  }
  sol = 0.0;
  dealii::SolverControl control(options_.eigenvalue_iterations, 0.0, false, false);
  dealii::SolverCG<VectorType> cg(control);
  double lambda = 0;
  cg.connect_eigenvalues_slot(
      [&](const std::vector<double>& ev) {
        for (const auto& e : ev)
          lambda = std::max(lambda, e);
      },
      false);
  dealii::DiagonalMatrix<VectorType> jacobi(inv);
  try {
    cg.solve(level.fast, sol, rhs, jacobi);
  } catch (const dealii::SolverControl::NoConvergence&) {
    // expected: only the Lanczos coefficients are wanted
  }
  // The largest Ritz value approaches λmax from below: a 10 % margin.
  level.lambda_max = 1.1 * lambda;
}

// Chebyshev–Jacobi on raw arrays; the products are the single-precision block copy's.
template <int dim>
void LatticeMultigrid<dim>::smooth(const Level& L, VectorType& xv, const VectorType& bv,
                                   bool zero_start) const {
  const double hi = L.lambda_max, lo = hi / options_.smoothing_range;
  const double theta = 0.5 * (hi + lo), half_width = 0.5 * (hi - lo);
  const double sigma = theta / half_width;
  double rho_old = 1.0 / sigma;
  const std::size_t n = L.n_particles * dim;
  double* x = xv.begin();
  const double* b = bv.begin();
  double* r = L.r.begin();
  double* d = L.tmp.begin();
  const double* inv = L.inverse_diagonal.data();
  L.fast.jacobi_residual(r, b, zero_start ? nullptr : x, inv);
  if (zero_start)
    for (std::size_t q = 0; q < n; ++q)
      x[q] = d[q] = r[q] / theta;
  else
    for (std::size_t q = 0; q < n; ++q)
      x[q] += (d[q] = r[q] / theta);
  for (unsigned int k = 2; k <= options_.smoother_degree; ++k) {
    L.fast.jacobi_residual(r, b, x, inv);
    const double rho = 1.0 / (2.0 * sigma - rho_old);
    const double a = rho * rho_old, c = 2.0 * rho / half_width;
    for (std::size_t q = 0; q < n; ++q)
      x[q] += (d[q] = a * d[q] + c * r[q]);
    rho_old = rho;
  }
}

template <int dim>
void LatticeMultigrid<dim>::v_cycle(unsigned int l, VectorType& x, const VectorType& b) const {
  if (l + 1 == levels_.size()) {
    coarse_solver_->solve(x, b);
    return;
  }
  const Level& L = *levels_[l];
  const Level& C = *levels_[l + 1];
  smooth(L, x, b, true);
  L.fast.jacobi_residual(L.r.begin(), b.begin(), x.begin(), nullptr); // r = b − K x
  C.prolongation.Tvmult(C.b, L.r);
  v_cycle(l + 1, C.x, C.b);
  C.prolongation.vmult(L.tmp, C.x);
  x += L.tmp;
  smooth(L, x, b, false);
}

template <int dim>
void LatticeMultigrid<dim>::vmult(VectorType& dst, const VectorType& src) const {
  if (levels_.empty())
    throw InvalidInput("LatticeMultigrid::vmult", "called before initialize",
                       "initialize(tangent, particles) first");
  if (levels_.size() == 1) {
    coarse_solver_->solve(dst, src);
    return;
  }
  v_cycle(0, dst, src);
}

template class LatticeMultigrid<2>;
template class LatticeMultigrid<3>;

} // namespace spinesim::meshfree
