#include "meshfree/lsmfm/lsmfm_solver.h"

#include "base/exceptions.h"
#include "fem/materials/j2_return_mapping.h"

#include <deal.II/base/symmetric_tensor.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace spinesim::meshfree {

namespace {

using Voigt = std::array<double, 6>;
using Tensor3 = dealii::Tensor<2, 3>;

// Voigt index of the tensor component (i, j) and back.
constexpr unsigned int voigt_index[3][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}};
constexpr unsigned int voigt_i[6] = {0, 1, 2, 0, 1, 0};
constexpr unsigned int voigt_j[6] = {0, 1, 2, 1, 2, 2};

Tensor3 to_tensor(const Voigt& v) {
  Tensor3 t;
  for (unsigned int a = 0; a < 6; ++a)
    t[voigt_i[a]][voigt_j[a]] = t[voigt_j[a]][voigt_i[a]] = v[a];
  return t;
}
Voigt to_voigt(const Tensor3& t) { // stress-like: tensor components
  Voigt v;
  for (unsigned int a = 0; a < 6; ++a)
    v[a] = 0.5 * (t[voigt_i[a]][voigt_j[a]] + t[voigt_j[a]][voigt_i[a]]);
  return v;
}
Voigt to_engineering(const Tensor3& t) { // strain-like: 2ε on the shears (eq. 16c)
  Voigt v = to_voigt(t);
  for (unsigned int a = 3; a < 6; ++a)
    v[a] *= 2.0;
  return v;
}

// C σ with C of eq. (16i) (engineering strain out).
Voigt compliance(const Voigt& s, double E, double nu) {
  const double mu = E / (2.0 * (1.0 + nu));
  Voigt e;
  e[0] = (s[0] - nu * (s[1] + s[2])) / E;
  e[1] = (s[1] - nu * (s[0] + s[2])) / E;
  e[2] = (s[2] - nu * (s[0] + s[1])) / E;
  for (unsigned int a = 3; a < 6; ++a)
    e[a] = s[a] / mu;
  return e;
}
double compliance_entry(unsigned int a, unsigned int b, double E, double nu) {
  if (a < 3 && b < 3)
    return a == b ? 1.0 / E : -nu / E;
  if (a == b)
    return 2.0 * (1.0 + nu) / E;
  return 0.0;
}
// σ^h + D R_u: the stress that satisfies the strain residual R_u = 0 with the strain and the
// plastic increment of the step held (σ^h scaled by E, R_u engineering strain; D = C⁻¹ of
// eq. 16i on the active components: plane stress keeps σ_zz = 0).
Voigt stress_from_strain_residual(const Voigt& sig_scaled, const Voigt& R, double E, double nu,
                                  bool plane_stress) {
  const double mu = E / (2.0 * (1.0 + nu));
  Voigt s;
  for (unsigned int a = 0; a < 6; ++a)
    s[a] = E * sig_scaled[a];
  if (plane_stress) {
    const double c = E / (1.0 - nu * nu);
    s[0] += c * (R[0] + nu * R[1]);
    s[1] += c * (R[1] + nu * R[0]);
    s[3] += mu * R[3];
    return s;
  }
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double tr = R[0] + R[1] + R[2];
  for (unsigned int a = 0; a < 3; ++a)
    s[a] += lambda * tr + 2.0 * mu * R[a];
  for (unsigned int a = 3; a < 6; ++a)
    s[a] += mu * R[a];
  return s;
}
// P of eq. (16f).
double projector_entry(unsigned int a, unsigned int b) {
  if (a < 3 && b < 3)
    return a == b ? 2.0 / 3.0 : -1.0 / 3.0;
  return a == b ? 2.0 : 0.0;
}
Voigt project(const Voigt& s) { // s̄ = P σ (eq. 16e)
  const double mean = (s[0] + s[1] + s[2]) / 3.0;
  return {{s[0] - mean, s[1] - mean, s[2] - mean, 2 * s[3], 2 * s[4], 2 * s[5]}};
}

// The coefficient of stress component v (Voigt) in the hoop terms of div σ in (r, z, θ):
// (σ_rr − σ_θθ)/r in the r row, σ_rz/r in the z row.
double hoop_sign(unsigned int v) {
  return v == 0 ? 1.0 : v == 2 ? -1.0 : v == 3 ? 1.0 : 0.0;
}

std::string point_text(const double* x, int dim) {
  std::ostringstream s;
  s << "(";
  for (int d = 0; d < dim; ++d)
    s << (d ? ", " : "") << x[d];
  s << ") m";
  return s.str();
}

} // namespace

template <int dim>
class LsmfmSolver<dim>::LinearSystem {
 public:
  Eigen::SparseMatrix<double> K;
  Eigen::VectorXd F;
  // Supernodal Cholesky (CHOLMOD; dense blocks through BLAS): the meshfree supports fill the
  // factor far more than a FEM stencil does, and the simplicial LDLT of Eigen spent two
  // thirds of a plastic run in its column loop (docs/lsmfm.md, the nonlinear solution). It also
  // tests positive definiteness: a Newton matrix that is not fails, and the step takes the
  // Gauss-Newton direction.
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> llt;
  // For a Gauss-Newton matrix that is positive semi-definite only at round-off (a pivot of
  // -1e-17 fails LLT but not LDLT): the simplicial LDLT, analysed when first needed.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  bool analysed = false, ldlt_analysed = false;

  // A matrix that is not positive definite is handled, not printed (CHOLMOD prints that
  // warning at any print level above 0); its errors are checked by factorize() below.
  LinearSystem() { llt.cholmod().print = 0; }
  // LLT of K; false if K is not positive definite. CHOLMOD's errors (out of memory, invalid
  // input) are a numerical failure naming the step, not a fall-back.
  bool factorize(unsigned int step, unsigned int iteration) {
    llt.factorize(K);
    if (llt.cholmod().status < 0)
      throw NumericalFailure("CHOLMOD failed to factorise the LSMFM system (status " +
                                 std::to_string(llt.cholmod().status) + ")",
                             "load step " + std::to_string(step) + ", iteration " +
                                 std::to_string(iteration),
                             "fewer nodes, or more memory");
    return llt.info() == Eigen::Success;
  }
};

template <int dim>
LsmfmSolver<dim>::LsmfmSolver(const LsmfmParameters& parameters, const Material& material,
                              std::vector<dealii::Point<dim>> nodes,
                              const std::vector<double>& spacing,
                              std::vector<dealii::Point<dim>> points, std::vector<double> weights)
    : prm_(parameters), mat_(material), mls_(
                                            nodes,
                                            [&] {
                                              std::vector<double> h(spacing.size());
                                              for (unsigned int j = 0; j < h.size(); ++j)
                                                h[j] = parameters.support_ratio * spacing[j];
                                              return h;
                                            }(),
                                            parameters.max_condition_number),
      points_(std::move(points)), weights_(std::move(weights)),
      system_(std::make_unique<LinearSystem>()) {
  prm_.validate();
  if (!(mat_.youngs_modulus > 0) || !(mat_.poisson_ratio > -1 && mat_.poisson_ratio < 0.5))
    throw InvalidInput("Material",
                       "E = " + std::to_string(mat_.youngs_modulus) +
                           " Pa, nu = " + std::to_string(mat_.poisson_ratio),
                       "E > 0 and -1 < nu < 0.5");
  if (std::isfinite(mat_.yield_stress) && !(mat_.hardening_modulus > 0) &&
      prm_.flow_rule == "complementary")
    throw InvalidInput("Material/Hardening modulus",
                       "= " + std::to_string(mat_.hardening_modulus) +
                           " Pa: the complementary flow rule of Kwon & Youn (2005, eq. 27) has "
                           "1/K̄ and holds no perfectly plastic solid",
                       "a hardening modulus > 0 [Pa], or LSMFM/Flow rule residual = "
                       "return_mapping");
  if (points_.size() != weights_.size() || points_.empty())
    throw InvalidInput("LSMFM integration",
                       std::to_string(points_.size()) + " points, " +
                           std::to_string(weights_.size()) + " weights",
                       "one weight per point, at least one point");
  if (dim == 3)
    active_ = {0, 1, 2, 3, 4, 5};
  else if (prm_.plane_model == "plane_stress")
    active_ = {0, 1, 3};
  else
    active_ = {0, 1, 2, 3};
  block_ = dim + active_.size();
  axisymmetric_ = dim == 2 && prm_.plane_model == "axisymmetric";
  if (axisymmetric_)
    for (unsigned int j = 0; j < mls_.nodes().size(); ++j)
      if (!(mls_.nodes()[j][0] > 0)) {
        double c[dim];
        for (unsigned int d = 0; d < dim; ++d)
          c[d] = mls_.nodes()[j][d];
        throw InvalidInput("LSMFM axisymmetric model",
                           "node " + std::to_string(j) + " at " + point_text(c, dim) +
                               " lies on or across the axis r = 0",
                           "a body at r > 0 (x is the radius): the hoop terms 1/r are singular "
                           "on the axis, so a solid cylinder is not supported");
      }
  if (axisymmetric_)
    for (unsigned int q = 0; q < points_.size(); ++q) {
      if (!(points_[q][0] > 0)) {
        double c[dim];
        for (unsigned int d = 0; d < dim; ++d)
          c[d] = points_[q][d];
        throw InvalidInput("LSMFM axisymmetric model",
                           "integration point " + std::to_string(q) + " at " + point_text(c, dim) +
                               " lies on or across the axis r = 0",
                           "a body at r > 0 (x is the radius): the hoop terms 1/r are singular "
                           "on the axis, so a solid cylinder is not supported");
      }
      weights_[q] *= 2.0 * dealii::numbers::PI * points_[q][0]; // the ring's volume element
    }
  return_mapping_ = prm_.flow_rule == "return_mapping";
  jaumann_log_ = prm_.finite_strain() && prm_.stress_rate == "jaumann_log";
  if (jaumann_log_ && !return_mapping_)
    throw InvalidInput("LSMFM/Stress rate",
                       "jaumann_log with Flow rule residual = complementary: the complementary "
                       "residual is the Truesdell form of Kwon & Youn (eq. 53)",
                       "truesdell, or Flow rule residual = return_mapping");
  if (std::isfinite(mat_.yield_stress))
    hardening_ =
        std::make_unique<materials::IsotropicHardening>(mat_.yield_stress, mat_.hardening_modulus);
  n_unknowns_ = block_ * mls_.nodes().size();
  // ℓ: the diagonal of the bounding box unless given.
  dealii::Point<dim> lo = mls_.nodes()[0], hi = lo;
  for (const auto& x : mls_.nodes())
    for (unsigned int d = 0; d < dim; ++d) {
      lo[d] = std::min(lo[d], x[d]);
      hi[d] = std::max(hi[d], x[d]);
    }
  ell_ = prm_.equilibrium_length > 0 ? prm_.equilibrium_length : lo.distance(hi);

  point_sites_.reserve(points_.size());
  for (unsigned int q = 0; q < points_.size(); ++q)
    point_sites_.push_back(make_site(points_[q], "integration point " + std::to_string(q)));
  node_sites_.reserve(mls_.nodes().size());
  for (unsigned int j = 0; j < mls_.nodes().size(); ++j)
    node_sites_.push_back(make_site(mls_.nodes()[j], "node " + std::to_string(j)));
  state_.resize(points_.size());
  plastic_set_.assign(points_.size(), 0);
  trial_excess_.assign(points_.size(), 0.0);
  flowed_.assign(points_.size(), 0);
  for (auto& s : state_)
    s.F_n = dealii::unit_symmetric_tensor<3>();
  U_.assign(n_unknowns_, 0.0);
  U_n_ = U_;
}

template <int dim>
LsmfmSolver<dim>::~LsmfmSolver() = default;

template <int dim>
typename LsmfmSolver<dim>::Site LsmfmSolver<dim>::make_site(const dealii::Point<dim>& x,
                                                            const std::string& what) const {
  typename MlsApproximation<dim>::Values v;
  if (!mls_.evaluate(x, v)) {
    double c[dim];
    for (unsigned int d = 0; d < dim; ++d)
      c[d] = x[d];
    throw NumericalFailure(
        "MLS moment matrix singular (" + std::to_string(v.nodes.size()) +
            " nodes cover the point, condition number " + std::to_string(v.condition_number) + ")",
        what + " at " + point_text(c, dim),
        "raise LSMFM/Support ratio, or check that every integration point lies inside the "
        "node cloud");
  }
  Site s;
  s.nodes = std::move(v.nodes);
  s.value = std::move(v.value);
  s.gradient = std::move(v.gradient);
  return s;
}

template <int dim>
void LsmfmSolver<dim>::set_conditions(std::vector<DisplacementCondition> displacement,
                                      std::vector<TractionCondition> traction) {
  const auto same_nodes = [](const auto& a, const auto& b) {
    if (a.size() != b.size())
      return false;
    for (unsigned int i = 0; i < a.size(); ++i)
      if (a[i].node != b[i].node)
        return false;
    return true;
  };
  const bool rebuild = !system_->analysed || !same_nodes(displacement, u_conditions_) ||
                       !same_nodes(traction, t_conditions_);
  for (const auto& c : displacement)
    if (c.node >= n_nodes() || !std::isfinite(c.value))
      throw InvalidInput("LSMFM boundary conditions",
                         "displacement condition at node " + std::to_string(c.node) +
                             " with value " + std::to_string(c.value),
                         "a node below " + std::to_string(n_nodes()) + " and a finite value [m]");
  for (const auto& c : traction)
    if (c.node >= n_nodes() || !std::isfinite(c.value) || !(c.stiffness >= 0) ||
        !std::isfinite(c.stiffness))
      throw InvalidInput("LSMFM boundary conditions",
                         "traction condition at node " + std::to_string(c.node) + " with value " +
                             std::to_string(c.value),
                         "a node below " + std::to_string(n_nodes()) +
                             ", a finite value [Pa] and a finite stiffness >= 0 [Pa/m]");
  u_conditions_ = std::move(displacement);
  t_conditions_ = std::move(traction);
  if (rebuild)
    build_pattern();
}

template <int dim>
void LsmfmSolver<dim>::build_pattern() {
  const unsigned int N = n_nodes();
  std::vector<std::vector<unsigned int>> adjacency(N);
  const auto add_site = [&](const Site& s) {
    for (unsigned int j : s.nodes)
      adjacency[j].insert(adjacency[j].end(), s.nodes.begin(), s.nodes.end());
  };
  for (const auto& s : point_sites_)
    add_site(s);
  for (const auto& c : u_conditions_)
    add_site(node_sites_[c.node]);
  for (const auto& c : t_conditions_)
    add_site(node_sites_[c.node]);
  for (unsigned int j = 0; j < N; ++j) {
    auto& a = adjacency[j];
    a.push_back(j); // keeps the diagonal block even for a node no site covers
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  // Column c = J·block + b holds rows I·block + a, I in adjacency[J] (ascending).
  auto& K = system_->K;
  K.resize(n_unknowns_, n_unknowns_);
  Eigen::VectorXi per_column(n_unknowns_);
  for (unsigned int j = 0; j < N; ++j)
    for (unsigned int b = 0; b < block_; ++b)
      per_column[j * block_ + b] = adjacency[j].size() * block_;
  K.reserve(per_column);
  for (unsigned int j = 0; j < N; ++j)
    for (unsigned int b = 0; b < block_; ++b)
      for (unsigned int i : adjacency[j])
        for (unsigned int a = 0; a < block_; ++a)
          K.insert(i * block_ + a, j * block_ + b) = 0.0;
  K.makeCompressed();
  const auto set_offsets = [&](Site& s) {
    const unsigned int n = s.nodes.size();
    s.pair_offset.resize(n * n);
    for (unsigned int jl = 0; jl < n; ++jl) {
      const auto& a = adjacency[s.nodes[jl]];
      for (unsigned int il = 0; il < n; ++il)
        s.pair_offset[il * n + jl] = std::lower_bound(a.begin(), a.end(), s.nodes[il]) - a.begin();
    }
  };
  for (auto& s : point_sites_)
    set_offsets(s);
  for (auto& s : node_sites_)
    set_offsets(s);
  system_->F.resize(n_unknowns_);
  system_->analysed = false;
  system_->llt.analyzePattern(K);
  system_->ldlt_analysed = false;
  system_->analysed = true;
}

template <int dim>
dealii::Tensor<2, 3>
LsmfmSolver<dim>::incremental_gradient(const Site& s, const std::vector<double>& U,
                                       const Tensor3& F_n_inverse, double r_n) const {
  // G = ∂ũ/∂x^n = Σ_J ũ_J ⊗ F_n⁻ᵀ ∇_X ψ_J; axisymmetric: G_θθ = ũ_r / r_n (f_θθ = r_{n+1}/r_n).
  Tensor3 G;
  if (axisymmetric_)
    for (unsigned int k = 0; k < s.nodes.size(); ++k) {
      const unsigned int base = s.nodes[k] * block_;
      G[2][2] += s.value[k] * (U[base] - U_n_[base]) / r_n;
    }
  for (unsigned int k = 0; k < s.nodes.size(); ++k) {
    const unsigned int base = s.nodes[k] * block_;
    dealii::Tensor<1, 3> g;
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < dim; ++j)
        g[i] += F_n_inverse[j][i] * s.gradient[k][j];
    for (unsigned int i = 0; i < dim; ++i) {
      const double du = U[base + i] - U_n_[base + i];
      for (unsigned int j = 0; j < 3; ++j)
        G[i][j] += du * g[j];
    }
  }
  return G;
}

template <int dim>
double LsmfmSolver<dim>::radius_n(unsigned int q) const {
  // F_n is the identity in small strain (the reference radius) and carries r_n/R in finite.
  return points_[q][0] * state_[q].F_n[2][2];
}

template <int dim>
typename LsmfmSolver<dim>::ReturnMapped LsmfmSolver<dim>::return_map(const Voigt& etr, double q,
                                                                     int branch) const {
  ReturnMapped out;
  const double E = mat_.youngs_modulus, nu = mat_.poisson_ratio;
  const double K = E / (3 * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  dealii::SymmetricTensor<2, 3> e;
  for (unsigned int a = 0; a < 6; ++a)
    e[voigt_i[a]][voigt_j[a]] = a < 3 ? etr[a] : 0.5 * etr[a];
  const bool plane_stress = dim == 2 && prm_.plane_model == "plane_stress";
  const auto map = [&](materials::J2ReturnResult& r) {
    if (std::isfinite(mat_.yield_stress) && branch == 0) {
      r = materials::j2_radial_return(e, q, K, mu, *hardening_, "LSMFM J2");
    } else if (branch == 2) {
      // The plastic branch of the radial return continued to Δγ < 0 (linear hardening:
      // Δγ = (q_tr − σ_y,n)/(3μ + H)), smooth wherever s_tr != 0, with the same consistent
      // tangent as fem/materials/j2_return_mapping.h.
      const double H = mat_.hardening_modulus, sy = mat_.yield_stress + H * q;
      const auto ed = dealii::deviator(e);
      const double norm = ed.norm();
      const auto I = dealii::unit_symmetric_tensor<3>();
      r.tangent = K * dealii::outer_product(I, I) + 2.0 * mu * dealii::deviator_tensor<3>();
      r.stress = r.tangent * e;
      if (norm > 0) {
        const auto nhat = ed / norm;
        const double q_tr = std::sqrt(1.5) * 2.0 * mu * norm;
        const double dg = (q_tr - sy) / (3.0 * mu + H);
        r.delta_gamma = dg;
        r.plastic_strain_increment = dg * std::sqrt(1.5) * nhat;
        r.stress -= 2.0 * mu * r.plastic_strain_increment;
        r.tangent =
            K * dealii::outer_product(I, I) +
            2.0 * mu * (1.0 - 3.0 * mu * dg / q_tr) * dealii::deviator_tensor<3>() +
            6.0 * mu * mu * (dg / q_tr - 1.0 / (3.0 * mu + H)) * dealii::outer_product(nhat, nhat);
        r.plastic = true;
      }
    } else {
      r.tangent = (K - 2.0 * mu / 3.0) * dealii::outer_product(dealii::unit_symmetric_tensor<3>(),
                                                               dealii::unit_symmetric_tensor<3>()) +
                  2.0 * mu * dealii::identity_tensor<3>();
      r.stress = r.tangent * e;
    }
  };
  materials::J2ReturnResult r;
  map(r);
  if (plane_stress) {
    // σ_zz = 0 by Newton on the trial ε_zz (the thickness strain is free in plane stress).
    e[2][2] = -nu / (1 - nu) * (e[0][0] + e[1][1]);
    for (unsigned int it = 0;; ++it) {
      map(r);
      const double szz = r.stress[2][2], dzz = r.tangent[2][2][2][2];
      if (std::abs(szz) <= 1e-13 * (r.stress.norm() + 1e-300) || it == 30)
        break;
      e[2][2] -= szz / dzz;
    }
  }
  for (unsigned int a = 0; a < 6; ++a) {
    out.stress[a] = r.stress[voigt_i[a]][voigt_j[a]];
    out.plastic_strain[a] =
        (a < 3 ? 1.0 : 2.0) * r.plastic_strain_increment[voigt_i[a]][voigt_j[a]];
    for (unsigned int b = 0; b < 6; ++b)
      out.tangent[a][b] = r.tangent[voigt_i[a]][voigt_j[a]][voigt_i[b]][voigt_j[b]];
  }
  if (plane_stress) { // condense ε_zz out: D_ab − D_a,zz D_zz,b / D_zz,zz
    const double dzz = out.tangent[2][2];
    double D[6][6];
    for (unsigned int a = 0; a < 6; ++a)
      for (unsigned int b = 0; b < 6; ++b)
        D[a][b] = (a == 2 || b == 2)
                      ? 0.0
                      : out.tangent[a][b] - out.tangent[a][2] * out.tangent[2][b] / dzz;
    std::copy(&D[0][0], &D[0][0] + 36, &out.tangent[0][0]);
    out.stress[2] = 0;
  }
  out.delta_q = r.delta_gamma;
  out.plastic = r.plastic;
  return out;
}

template <int dim>
double LsmfmSolver<dim>::evaluate(const std::vector<double>& U, bool assemble,
                                  unsigned int* plastic) {
  const double E = mat_.youngs_modulus, nu = mat_.poisson_ratio;
  const bool finite = prm_.finite_strain();
  const bool can_yield = std::isfinite(mat_.yield_stress);
  const unsigned int nr = active_.size();
  const unsigned int rows = nr + dim;
  auto& K = system_->K;
  double* values = K.valuePtr();
  const int* outer = K.outerIndexPtr();
  if (assemble) {
    std::fill(values, values + K.nonZeros(), 0.0);
    system_->F.setZero();
  }
  if (plastic)
    *plastic = 0;
  // Adds W·(JᵀJ + S) and −W·Jᵀr of one site; S (optional, on the stress unknowns of the
  // site's nodes: ψ_k ψ_l S_ab) is the second-order part Σ_a r_a ∇²r_a of the Hessian.
  const auto scatter = [&](const Site& s, const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                           double W, const double(*S)[6]) {
    const unsigned int n = s.nodes.size();
    Eigen::MatrixXd KL = W * (J.transpose() * J);
    const Eigen::VectorXd FL = -W * (J.transpose() * r);
    if (S)
      for (unsigned int k = 0; k < n; ++k)
        for (unsigned int l = 0; l < n; ++l)
          for (unsigned int a = 0; a < nr; ++a)
            for (unsigned int b = 0; b < nr; ++b)
              KL(k * block_ + dim + a, l * block_ + dim + b) +=
                  W * s.value[k] * s.value[l] * S[active_[a]][active_[b]];
    for (unsigned int jl = 0; jl < n; ++jl)
      for (unsigned int b = 0; b < block_; ++b) {
        const unsigned int col = s.nodes[jl] * block_ + b;
        system_->F[col] += FL[jl * block_ + b];
        for (unsigned int il = 0; il < n; ++il) {
          const int offset = outer[col] + s.pair_offset[il * n + jl] * block_;
          for (unsigned int a = 0; a < block_; ++a)
            values[offset + a] += KL(il * block_ + a, jl * block_ + b);
        }
      }
  };

  double I = 0;
  Eigen::MatrixXd J;
  Eigen::VectorXd r(rows);
  // The entries (i, j) of the displacement gradient the strain residual depends on: the
  // in-plane ones, and the hoop entry θθ when axisymmetric.
  std::vector<std::pair<unsigned int, unsigned int>> gradient_entries;
  for (unsigned int i = 0; i < dim; ++i)
    for (unsigned int j = 0; j < dim; ++j)
      gradient_entries.emplace_back(i, j);
  if (axisymmetric_)
    gradient_entries.emplace_back(2, 2);
  for (unsigned int q = 0; q < points_.size(); ++q) {
    const Site& s = point_sites_[q];
    const PointState& st = state_[q];
    const unsigned int n = s.nodes.size();
    // Axisymmetric: the radius at t_n (the hoop gradient's scale) and at the iterate (the
    // hoop terms of div σ); unused otherwise.
    const double r_hoop = axisymmetric_ ? radius_n(q) : 1.0;
    double r_now = r_hoop;
    // Stress (scaled by E) and gradients in the configuration at t_n.
    Voigt sig{};
    const Tensor3 Fn_inv = finite ? dealii::invert(st.F_n) : dealii::unit_symmetric_tensor<3>();
    const double Jn = finite ? dealii::determinant(st.F_n) : 1.0;
    std::vector<dealii::Tensor<1, 3>> g(n);
    for (unsigned int k = 0; k < n; ++k) {
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int j = 0; j < dim; ++j)
          g[k][i] += Fn_inv[j][i] * s.gradient[k][j];
      const unsigned int base = s.nodes[k] * block_ + dim;
      for (unsigned int a = 0; a < nr; ++a)
        sig[active_[a]] += s.value[k] * U[base + a];
    }
    // Strain residual part and its derivative in the displacement gradient H (small strain:
    // H = ∇u, R = ε(H); finite strain: H = G = ∂ũ/∂x^n, eq. 53).
    Voigt R{};
    Tensor3 f_inv = dealii::unit_symmetric_tensor<3>();
    std::array<std::array<Voigt, 3>, 3> dR_dH{};
    if (!finite) {
      Tensor3 H;
      for (unsigned int k = 0; k < n; ++k) {
        const unsigned int base = s.nodes[k] * block_;
        for (unsigned int i = 0; i < dim; ++i)
          for (unsigned int j = 0; j < 3; ++j)
            H[i][j] += U[base + i] * g[k][j];
        if (axisymmetric_)
          H[2][2] += s.value[k] * U[base] / r_hoop; // ε_θθ = u_r / r
      }
      R = to_engineering(H);
      const Voigt c = compliance(sig, 1.0, nu); // C σ with σ scaled by E: (E C)(σ/E)
      for (unsigned int a = 0; a < 6; ++a)
        R[a] -= st.ep[a] + c[a];
      for (const auto& [i, j] : gradient_entries) {
        Tensor3 e;
        e[i][j] = 1.0;
        dR_dH[i][j] = to_engineering(e);
      }
    } else {
      const Tensor3 G = incremental_gradient(s, U, Fn_inv, r_hoop);
      const Tensor3 f = dealii::unit_symmetric_tensor<3>() + G;
      r_now = r_hoop * f[2][2];
      const double Jt = dealii::determinant(f);
      if (!(Jt > 0)) {
        double c[dim];
        for (unsigned int d = 0; d < dim; ++d)
          c[d] = points_[q][d];
        throw NumericalFailure(
            "incremental deformation inverts the material (det f = " + std::to_string(Jt) + ")",
            "integration point " + std::to_string(q) + " at " + point_text(c, dim),
            "take more load steps");
      }
      f_inv = dealii::invert(f);
      const Tensor3 M = dealii::transpose(f_inv) * f_inv;
      Voigt sig_n_scaled = st.sigma_n;
      for (double& v : sig_n_scaled)
        v /= E;
      const Tensor3 sn = to_tensor(sig_n_scaled);
      const Tensor3 sbar = f * sn * dealii::transpose(f);
      R = to_engineering(0.5 * (dealii::unit_symmetric_tensor<3>() - M));
      const Voigt c = compliance(sig, 1.0, nu);
      const Voigt cbar = compliance(to_voigt(sbar), 1.0, nu);
      for (unsigned int a = 0; a < 6; ++a)
        R[a] += -c[a] + cbar[a] / Jt;
      for (const auto& [i, j] : gradient_entries) {
        Tensor3 e;
        e[i][j] = 1.0;
        // δε̃ = sym(M δG f⁻¹); δ(σ̄/J̃) = (δG σ_n fᵀ + f σ_n δGᵀ)/J̃ − σ̄ tr(f⁻¹δG)/J̃.
        const Tensor3 de = M * e * f_inv;
        const Tensor3 dsbar = e * sn * dealii::transpose(f) + f * sn * dealii::transpose(e);
        const Tensor3 dq = dsbar / Jt - sbar * (f_inv[j][i] / Jt);
        const Voigt dcbar = compliance(to_voigt(dq), 1.0, nu);
        dR_dH[i][j] = to_engineering(0.5 * (de + dealii::transpose(de)));
        for (unsigned int a = 0; a < 6; ++a)
          dR_dH[i][j][a] += dcbar[a];
      }
      if (jaumann_log_) {
        // Rotation-neutralised update with logarithmic strain increments (the objective
        // update of Abaqus' hypoelastic J2 with the Jaumann rate, Hughes & Winget 1980 in the
        // polar form of Rashid 1993): e_tr = ln Ṽ + C(R̃ σ_n R̃ᵀ), f = Ṽ R̃; the derivative
        // in G by central differences (a smooth function of G; step 1e-7).
        const auto trial = [&](const Tensor3& Gx) {
          const Tensor3 fx = dealii::unit_symmetric_tensor<3>() + Gx;
          const auto eig =
              dealii::eigenvectors(dealii::symmetrize(Tensor3(fx * dealii::transpose(fx))));
          Tensor3 logV, Vinv;
          for (const auto& [lambda, v] : eig) {
            logV += 0.5 * std::log(lambda) * dealii::outer_product(v, v);
            Vinv += (1.0 / std::sqrt(lambda)) * dealii::outer_product(v, v);
          }
          const Tensor3 Rx = Vinv * fx;
          Voigt e = to_engineering(logV);
          const Voigt cr = compliance(to_voigt(Rx * sn * dealii::transpose(Rx)), 1.0, nu);
          for (unsigned int a = 0; a < 6; ++a)
            e[a] += cr[a];
          return e;
        };
        const Voigt c = compliance(sig, 1.0, nu);
        const Voigt e0 = trial(G);
        for (unsigned int a = 0; a < 6; ++a)
          R[a] = e0[a] - c[a];
        if (assemble)
          for (const auto& [i, j] : gradient_entries) {
            const double h = 1e-7;
            Tensor3 Gp = G, Gm = G;
            Gp[i][j] += h;
            Gm[i][j] -= h;
            const Voigt ep = trial(Gp), em = trial(Gm);
            for (unsigned int a = 0; a < 6; ++a)
              dR_dH[i][j][a] = (ep[a] - em[a]) / (2 * h);
          }
      }
    }
    // Return-mapping form: R_u = C σ_rm(e_tr) − C σ, with e_tr = R + Cσ the trial elastic
    // strain (small strain: ε − e^p_n; finite strain: ε̃ + C(f σ_n fᵀ)/J̃, eq. 51 with
    // Δγ = 0) and σ_rm its J2 radial return (fem/materials/j2_return_mapping.h); the
    // derivative in H is C D ∂e_tr/∂H with D the consistent tangent.
    Voigt recorded{}; // return mapping: the stress this point commits (see below)
    if (return_mapping_) {
      const Voigt c = compliance(sig, 1.0, nu);
      Voigt etr;
      for (unsigned int a = 0; a < 6; ++a)
        etr[a] = R[a] + c[a];
      const int branch = !std::isfinite(mat_.yield_stress) ? 1
                         : iterate_switching_              ? 0
                         : plastic_set_[q]                 ? 2
                                                           : 1;
      const auto rm = return_map(etr, st.q, branch);
      if (record_ || assemble) {
        // Yield test of the trial state for the next plastic set: q_tr − σ_y,n.
        const auto trial = return_map(etr, st.q, 1);
        trial_excess_[q] =
            von_mises(trial.stress) - (mat_.yield_stress + mat_.hardening_modulus * st.q);
        // commit() books flow only where Δq > 0; elsewhere the point stays elastic, and so
        // does the stress it commits.
        recorded = rm.plastic && !(rm.delta_q > 0) ? trial.stress : rm.stress;
      }
      if (record_)
        returned_[q] = rm;
      const Voigt crm = compliance(rm.stress, E, nu);
      for (unsigned int a = 0; a < 6; ++a)
        R[a] = crm[a] - c[a];
      if (plastic && rm.plastic)
        ++*plastic;
      if (assemble) {
        // C·D on engineering strain: (C D)_ab = Σ_c C_ac D[c][b] (both in Voigt, D taking
        // engineering strain).
        double CD[6][6];
        for (unsigned int a = 0; a < 6; ++a)
          for (unsigned int b = 0; b < 6; ++b) {
            double v = 0;
            for (unsigned int k = 0; k < 6; ++k)
              v += compliance_entry(a, k, E, nu) * rm.tangent[k][b];
            CD[a][b] = v;
          }
        for (const auto& [i, j] : gradient_entries) {
          Voigt d{};
          for (unsigned int a = 0; a < 6; ++a)
            for (unsigned int b = 0; b < 6; ++b)
              d[a] += CD[a][b] * dR_dH[i][j][b];
          dR_dH[i][j] = d;
        }
      }
    }
    // Plasticity at the current stress (eqs. 40–41a) and Σ of eq. (27), scaled by E.
    Voigt sigma;
    for (unsigned int a = 0; a < 6; ++a)
      sigma[a] = E * sig[a];
    const Voigt sb = project(sigma);
    double fnorm = 0;
    for (unsigned int a = 0; a < 6; ++a)
      fnorm += sigma[a] * sb[a];
    fnorm = std::sqrt(std::max(fnorm, 0.0));
    double gamma = 0;
    Voigt nvec{};
    // The point flows when it is in the active set (solve_step decides the set; within a
    // Newton solve γ = cφ̃ holds on the whole plastic branch, of either sign).
    const double phi_now =
        fnorm - std::sqrt(2.0 / 3.0) * (mat_.yield_stress + mat_.hardening_modulus * st.q);
    const bool flows = !return_mapping_ && can_yield && fnorm > 0 &&
                       (iterate_switching_ ? phi_now > 0 : bool(plastic_set_[q]));
    if (record_ && !return_mapping_)
      plastic_set_[q] = flows;
    if (flows) {
      gamma = 1.5 * phi_now / mat_.hardening_modulus;
      for (unsigned int a = 0; a < 6; ++a)
        nvec[a] = sb[a] / fnorm;
      for (unsigned int a = 0; a < 6; ++a)
        R[a] -= gamma * nvec[a];
      if (plastic)
        ++*plastic;
    }
    if (record_ && finite) {
      if (return_mapping_) {
        constitutive_stress_[q] = recorded;
      } else {
        // commit() books flow only where φ > 0: a point of the set below the yield surface
        // (γ ≤ 0) commits the stress without that flow.
        Voigt committed = R;
        if (flows && !(phi_now > 0))
          for (unsigned int a = 0; a < 6; ++a)
            committed[a] += gamma * nvec[a];
        constitutive_stress_[q] =
            stress_from_strain_residual(sig, committed, E, nu, prm_.plane_model == "plane_stress");
      }
    }
    // Residual vector: active rows of R_u, then ℓ div σ / E in the current configuration.
    for (unsigned int a = 0; a < nr; ++a)
      r[a] = R[active_[a]];
    std::vector<dealii::Tensor<1, 3>> gc(n); // ∇ψ in the configuration of the iterate
    for (unsigned int k = 0; k < n; ++k)
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int j = 0; j < 3; ++j)
          gc[k][i] += f_inv[j][i] * g[k][j];
    for (unsigned int i = 0; i < dim; ++i)
      r[nr + i] = 0;
    for (unsigned int k = 0; k < n; ++k) {
      const unsigned int base = s.nodes[k] * block_ + dim;
      for (unsigned int a = 0; a < nr; ++a) {
        const unsigned int v = active_[a];
        const unsigned int i = voigt_i[v], j = voigt_j[v];
        const double c = U[base + a];
        if (i < dim)
          r[nr + i] += ell_ * c * gc[k][j];
        if (i != j && j < dim)
          r[nr + j] += ell_ * c * gc[k][i];
        if (axisymmetric_) // div σ in (r, z): + (σ_rr − σ_θθ)/r and + σ_rz/r
          r[nr + (v == 3 ? 1 : 0)] += ell_ * c * s.value[k] * hoop_sign(v) / r_now;
      }
    }
    const double W = weights_[q] * Jn;
    const double rr = r.squaredNorm();
    if (!std::isfinite(rr)) {
      double c[dim];
      for (unsigned int d = 0; d < dim; ++d)
        c[d] = points_[q][d];
      throw NumericalFailure("least-squares residual is not finite",
                             "integration point " + std::to_string(q) + " at " + point_text(c, dim),
                             "check the material constants and the boundary values; take more "
                             "load steps");
    }
    I += W * rr;
    if (!assemble)
      continue;

    // Jacobian: [∂R_u/∂u, −Σ̂ ψ; 0, ℓ B_s ψ] (eqs. 26, 28), Σ̂ = E Σ.
    double Sigma[6][6];
    for (unsigned int a = 0; a < 6; ++a)
      for (unsigned int b = 0; b < 6; ++b) {
        double v = compliance_entry(a, b, 1.0, nu);
        if (flows)
          v += E * (1.5 / mat_.hardening_modulus * nvec[a] * nvec[b] +
                    gamma / fnorm * (projector_entry(a, b) - nvec[a] * nvec[b]));
        Sigma[a][b] = v;
      }
    J.setZero(rows, n * block_);
    for (unsigned int k = 0; k < n; ++k) {
      const unsigned int c0 = k * block_;
      for (unsigned int a = 0; a < nr; ++a) {
        const unsigned int v = active_[a];
        for (unsigned int i = 0; i < dim; ++i) {
          double d = 0;
          for (unsigned int j = 0; j < dim; ++j)
            d += dR_dH[i][j][v] * g[k][j];
          J(a, c0 + i) = d;
        }
        if (axisymmetric_) // through G_θθ = ũ_r / r_n (ε_θθ = u_r / r in small strain)
          J(a, c0) += dR_dH[2][2][v] * s.value[k] / r_hoop;
        for (unsigned int b = 0; b < nr; ++b)
          J(a, c0 + dim + b) = -Sigma[v][active_[b]] * s.value[k];
      }
      for (unsigned int b = 0; b < nr; ++b) {
        const unsigned int v = active_[b];
        const unsigned int i = voigt_i[v], j = voigt_j[v];
        if (i < dim)
          J(nr + i, c0 + dim + b) += ell_ * gc[k][j];
        if (i != j && j < dim)
          J(nr + j, c0 + dim + b) += ell_ * gc[k][i];
        if (axisymmetric_)
          J(nr + (v == 3 ? 1 : 0), c0 + dim + b) += ell_ * s.value[k] * hoop_sign(v) / r_now;
      }
    }
    // Finite strain: div σ is taken in the configuration of the iterate, so its rows depend on
    // the displacements too. With ∇ψ_k = f⁻ᵀ g_k, ∂(∇ψ_k)/∂u_m,a = −(∇ψ_k)_a ∇ψ_m, so
    // ∂(div σ)_i/∂u_m,a = −Σ_j A_ija (∇ψ_m)_j with A_ija = Σ_k S_k,ij (∇ψ_k)_a (S_k node k's
    // stress coefficients); the hoop terms h/r at r = r_n + ũ_r add −h ψ_m / r². Without these
    // −Jᵀr is not the gradient of I where the residuals do not vanish: the iteration then
    // stops at a point that is not I's minimiser, and its direction need not descend along I,
    // which the line search measures.
    if (finite) {
      double A[dim][dim][dim] = {};
      double hoop[dim] = {};
      for (unsigned int k = 0; k < n; ++k) {
        const unsigned int base = s.nodes[k] * block_ + dim;
        for (unsigned int b = 0; b < nr; ++b) {
          const unsigned int v = active_[b];
          const unsigned int i = voigt_i[v], j = voigt_j[v];
          const double c = U[base + b];
          if (i < dim && j < dim)
            for (unsigned int a = 0; a < dim; ++a) {
              A[i][j][a] += c * gc[k][a];
              if (i != j)
                A[j][i][a] += c * gc[k][a];
            }
          if (axisymmetric_)
            hoop[v == 3 ? 1 : 0] += c * s.value[k] * hoop_sign(v);
        }
      }
      for (unsigned int m = 0; m < n; ++m)
        for (unsigned int i = 0; i < dim; ++i) {
          for (unsigned int a = 0; a < dim; ++a) {
            double d = 0;
            for (unsigned int j = 0; j < dim; ++j)
              d += A[i][j][a] * gc[m][j];
            J(nr + i, m * block_ + a) -= ell_ * d;
          }
          if (axisymmetric_)
            J(nr + i, m * block_) -= ell_ * hoop[i] * s.value[m] / (r_now * r_now);
        }
    }
    // Full Newton: the curvature of the flow direction. With g = γn, γ = c φ̃, c = 3/(2K̄),
    // H = ∂n/∂σ = (P − nnᵀ)/f and k = √(2/3)κ(q_n):
    //   Σ_a r_a ∂²g_a/∂σ² = c (k/f) [n (Hr)ᵀ + (Hr) nᵀ + (r·n) H],
    // and R_u = … − g, in σ/E: S = −E² of it. Gauss–Newton drops it (as eq. 20 does); across
    // the yield surface it is what bends the step along the surface: on the tangential
    // directions it is c|r·n|/f against (1/E)² from JᵀJ, larger as soon as the normal
    // residual exceeds f/(cE²) (3e-8 for E/K̄ = 3e5).
    if (second_order_ && flows) {
      double H[6][6], Hr[6] = {}, rn = 0;
      Voigt rf{};
      for (unsigned int a = 0; a < nr; ++a)
        rf[active_[a]] = r[a];
      for (unsigned int a = 0; a < 6; ++a) {
        rn += rf[a] * nvec[a];
        for (unsigned int b = 0; b < 6; ++b)
          H[a][b] = (projector_entry(a, b) - nvec[a] * nvec[b]) / fnorm;
      }
      for (unsigned int a = 0; a < 6; ++a)
        for (unsigned int b = 0; b < 6; ++b)
          Hr[a] += H[a][b] * rf[b];
      const double c = 1.5 / mat_.hardening_modulus;
      const double k_over_f = 1.0 - gamma / (c * fnorm); // φ̃ = γ/c = f − k
      double S[6][6];
      for (unsigned int a = 0; a < 6; ++a)
        for (unsigned int b = 0; b < 6; ++b)
          S[a][b] = -E * E * c * k_over_f * (nvec[a] * Hr[b] + Hr[a] * nvec[b] + rn * H[a][b]);
      scatter(s, J, r, W, S);
    } else {
      scatter(s, J, r, W, nullptr);
    }
  }

  // Penalties from the mean diagonal of the domain part (section 5.1), fixed at the first
  // assembly so that I keeps one meaning through the run.
  if (alpha_u_ < 0) {
    if (!assemble)
      throw std::logic_error("LsmfmSolver: penalties are set by the first assembly");
    double du = 0, ds = 0;
    for (unsigned int c = 0; c < n_unknowns_; ++c)
      ((c % block_) < dim ? du : ds) += K.coeff(c, c);
    const double nn = n_nodes();
    alpha_u_ = prm_.penalty_factor * du / (nn * dim);
    alpha_t_ = prm_.penalty_factor * ds / (nn * active_.size());
  }
  for (const auto& c : u_conditions_) {
    const Site& s = node_sites_[c.node];
    const unsigned int n = s.nodes.size();
    Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(1, n * block_);
    Eigen::VectorXd rb(1);
    double u = 0;
    for (unsigned int k = 0; k < n; ++k)
      for (unsigned int i = 0; i < dim; ++i) {
        u += c.direction[i] * s.value[k] * U[s.nodes[k] * block_ + i];
        Jb(0, k * block_ + i) = c.direction[i] * s.value[k];
      }
    rb[0] = u - c.value;
    I += alpha_u_ * rb[0] * rb[0];
    if (assemble)
      scatter(s, Jb, rb, alpha_u_, nullptr);
  }
  for (unsigned int t = 0; t < t_conditions_.size(); ++t) {
    const auto& c = t_conditions_[t];
    const Site& s = node_sites_[c.node];
    const unsigned int n = s.nodes.size();
    // Outward normal carried by the deformation at t_n: n ∝ F_n⁻ᵀ N.
    dealii::Tensor<1, dim> normal = c.normal;
    if (finite && !c.spatial_normal) {
      dealii::Tensor<2, dim> F = dealii::unit_symmetric_tensor<dim>();
      for (unsigned int k = 0; k < n; ++k)
        for (unsigned int i = 0; i < dim; ++i)
          for (unsigned int j = 0; j < dim; ++j)
            F[i][j] += U_n_[s.nodes[k] * block_ + i] * s.gradient[k][j];
      normal = dealii::transpose(dealii::invert(F)) * c.normal;
      normal /= normal.norm();
    }
    Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(1, n * block_);
    Eigen::VectorXd rb(1);
    double t_d = 0;
    for (unsigned int k = 0; k < n; ++k)
      for (unsigned int b = 0; b < active_.size(); ++b) {
        const unsigned int v = active_[b];
        const unsigned int i = voigt_i[v], j = voigt_j[v];
        // d·(σ n) for the unit component v: d_i n_j (+ d_j n_i off the diagonal).
        double coef = 0;
        if (i < dim && j < dim) {
          coef = c.direction[i] * normal[j];
          if (i != j)
            coef += c.direction[j] * normal[i];
        }
        t_d += coef * s.value[k] * U[s.nodes[k] * block_ + dim + b];
        Jb(0, k * block_ + dim + b) = coef * s.value[k];
      }
    if (c.stiffness != 0) // the spring's part, scaled by E like the traction
      for (unsigned int k = 0; k < n; ++k)
        for (unsigned int i = 0; i < dim; ++i) {
          const double coef = c.stiffness / E * c.direction[i] * s.value[k];
          t_d += coef * U[s.nodes[k] * block_ + i];
          Jb(0, k * block_ + i) = coef;
        }
    rb[0] = t_d - c.value / E;
    I += alpha_t_ * rb[0] * rb[0];
    if (assemble)
      scatter(s, Jb, rb, alpha_t_, nullptr);
  }
  return I;
}

template <int dim>
typename LsmfmSolver<dim>::StepResult LsmfmSolver<dim>::solve_step() {
  const StepResult result = solve_trial();
  accept_step();
  return result;
}

template <int dim>
void LsmfmSolver<dim>::accept_step() {
  if (!open_step_)
    throw std::logic_error("LsmfmSolver::accept_step without solve_trial");
  commit();
  open_step_ = false;
}

template <int dim>
typename LsmfmSolver<dim>::StepResult LsmfmSolver<dim>::solve_trial() {
  // A failed trial closes the step and leaves the last committed state.
  const bool opens = !open_step_;
  try {
    return trial();
  } catch (...) {
    open_step_ = false;
    U_ = U_n_;
    if (opens)
      --step_; // the step it opened is not taken
    throw;
  }
}

template <int dim>
typename LsmfmSolver<dim>::StepResult LsmfmSolver<dim>::trial() {
  // A second trial of the same load step starts from the first one's solution.
  const bool retry = open_step_;
  if (!retry)
    ++step_;
  open_step_ = true;
  if (!system_->analysed)
    build_pattern();
  StepResult result;
  // The plastic set starts as the points that flowed in the last step.
  plastic_set_ = flowed_;
  // The scale of the step: the gradient of I at the last converged state under the new
  // boundary values.
  evaluate(U_n_, true, nullptr);
  const double g0 = system_->F.norm();
  // Predictor: the last increment again, when that lowers I: in steady plastic flow it
  // starts Newton close to the solution.
  if (!retry && !last_increment_.empty()) {
    std::vector<double> trial(n_unknowns_);
    const double I_n = evaluate(U_, false, nullptr);
    for (unsigned int i = 0; i < n_unknowns_; ++i)
      trial[i] = U_[i] + last_increment_[i];
    double I_p = std::numeric_limits<double>::infinity();
    try {
      I_p = evaluate(trial, false, nullptr);
    } catch (const NumericalFailure&) {
    }
    if (I_p < I_n)
      U_.swap(trial);
  }
  // Active-set iteration. Kwon & Youn decide elastic or plastic at every Newton iterate
  // from the current stress (eq. 40); I is then only piecewise smooth, with a kink of slope
  // ratio cE = 1.5 E/K̄ at the yield surface, and Newton stalls near it for small K̄
  // (measured on the finite extension, E/K̄ = 3e5: no convergence in 40 iterations from the
  // first plastic step on, already at E/K̄ = 3e3). Here the set is held fixed during a
  // Newton solve, which makes I smooth, and updated between solves until it is consistent
  // to LSMFM/Yield tolerance: every point of the set has φ̃ >= −tol σ_Y and every other
  // point φ̃ <= tol σ_Y (eqs. 40-41 to that tolerance).
  // The yield test of every point: φ̃ for the complementary form (current stress), the
  // trial excess for the return-mapping form (radial return), both in Pa.
  std::vector<double> phi(points_.size(), 0.0);
  const auto violation = [&]() {
    double worst = 0;
    for (unsigned int q = 0; q < points_.size(); ++q) {
      if (return_mapping_) {
        phi[q] = trial_excess_[q];
      } else {
        const Voigt sigma = point_stress(q);
        const Voigt sb = project(sigma);
        double f = 0;
        for (unsigned int a = 0; a < 6; ++a)
          f += sigma[a] * sb[a];
        f = std::sqrt(std::max(f, 0.0));
        // φ̃ of eq. (40) over √(2/3): in units of the uniaxial yield stress.
        phi[q] = std::sqrt(1.5) * f - (mat_.yield_stress + mat_.hardening_modulus * state_[q].q);
      }
      if (plastic_set_[q] ? phi[q] < 0 : phi[q] > 0)
        worst = std::max(worst, std::abs(phi[q]));
    }
    return worst;
  };
  // Two measures keep the set iteration from oscillating:
  //  * only the violators within a factor 2 of the worst one change sides. Flipping all of
  //    them overshoots: on the perforated plate (complementary form, t = 0.36) the set swung
  //    8 → 80 → 28 → 68 → 28 → 76 points, each solve relaxing too much or too little stress;
  //  * a set whose worst violation is below the tolerance is accepted. Near a kink of I the
  //    last few points can cycle at violations of 1e-4..3e-3 σ_Y (measured on the same
  //    plate) without any consistent set in reach. The floor 1e-10 σ_Y is round-off.
  const double yield_tolerance = std::max(prm_.yield_tolerance, 1e-10) * mat_.yield_stress;
  const auto update_set = [&]() {
    const double worst = violation();
    result.max_yield_violation = worst;
    if (worst <= yield_tolerance)
      return 0u;
    unsigned int changed = 0;
    for (unsigned int q = 0; q < points_.size(); ++q)
      if ((plastic_set_[q] ? phi[q] < 0 : phi[q] > 0) && std::abs(phi[q]) >= 0.5 * worst) {
        plastic_set_[q] = !plastic_set_[q];
        ++changed;
      }
    return changed;
  };
  // A set can cycle (measured on the perforated plate: a period of four solves with 4 to 28
  // points near φ̃ = 0 changing sides). A set seen before ends the active-set iteration; the
  // last Newton solve then decides the set at every iterate, as eq. (40) does, starting
  // from the active-set solution, where only those few points lie near the kink.
  std::set<std::vector<char>> seen{plastic_set_};
  unsigned int total = 0;
  for (unsigned int round = 0;; ++round) {
    newton(result, g0);
    total += result.iterations;
    if (!std::isfinite(mat_.yield_stress) || update_set() == 0)
      break;
    ++result.set_updates;
    if (!seen.insert(plastic_set_).second || round == prm_.max_iterations) {
      ++result.set_fallbacks;
      iterate_switching_ = true;
      try {
        newton(result, g0);
      } catch (...) {
        iterate_switching_ = false;
        throw;
      }
      iterate_switching_ = false;
      total += result.iterations;
      break;
    }
  }
  result.iterations = total;
  return result;
}

template <int dim>
void LsmfmSolver<dim>::newton(StepResult& result, double g0) {
  std::vector<double> trial(n_unknowns_), history;
  double last_update = std::numeric_limits<double>::infinity();
  for (unsigned int it = 0;; ++it) {
    unsigned int plastic = 0;
    const double I = evaluate(U_, true, &plastic);
    const double g = system_->F.norm();
    result.iterations = it;
    result.functional = I;
    result.plastic_points = plastic;
    result.relative_gradient = g0 > 0 ? g / g0 : 0.0;
    // Converged: the gradient of I has fallen by the tolerance; or the last update was
    // below the update tolerance of the step's increment (displacement and stress each)
    // with the gradient down by 1e-4. The second ends Gauss–Newton's linear tail at a
    // minimum with a non-zero residual (measured on the perforated plate: rate 0.7 per
    // iteration with I settled to 9 digits) and the chatter of points on the yield surface
    // at a kink of I, where the gradient need not vanish.
    const bool small_update =
        it > 0 && last_update <= prm_.update_tolerance && result.relative_gradient <= 1e-4;
    if (g == 0 || result.relative_gradient <= prm_.tolerance || small_update)
      break;
    // Iterate-wise switching only: points chattering across the yield surface keep the
    // updates from shrinking while I has settled. Five iterations that lower I by less than
    // 1e-6 of itself, with the gradient down by 1e-5, end the solve as a stall at a kink of
    // I (counted, and reported by the caller).
    history.push_back(I);
    if (iterate_switching_ && history.size() > 5 && history[history.size() - 6] - I <= 1e-6 * I &&
        result.relative_gradient <= 1e-5) {
      ++result.kink_stops;
      break;
    }
    if (it == prm_.max_iterations) {
      std::ostringstream what;
      what << "LSMFM Newton did not converge in " << it << " iterations (|grad I| at "
           << result.relative_gradient << " of its start, tolerance " << prm_.tolerance << ")";
      throw NumericalFailure(what.str(), "load step " + std::to_string(step_),
                             "take more load steps, or raise LSMFM/Max iterations");
    }
    // Newton direction with the second-order term; Gauss–Newton (always a descent direction,
    // JᵀJ being positive semi-definite) when that matrix is not positive definite or its
    // direction does not descend.
    auto& llt = system_->llt;
    Eigen::VectorXd dU;
    bool newton_ok = false;
    if (plastic > 0) {
      if (system_->factorize(step_, it)) {
        dU = llt.solve(system_->F);
        newton_ok = system_->F.dot(dU) > 0;
      }
      if (!newton_ok) {
        second_order_ = false;
        evaluate(U_, true, nullptr);
        second_order_ = true;
      }
    }
    if (!newton_ok) {
      if (system_->factorize(step_, it))
        dU = llt.solve(system_->F);
      else {
        auto& ldlt = system_->ldlt;
        if (!system_->ldlt_analysed) {
          ldlt.analyzePattern(system_->K);
          system_->ldlt_analysed = true;
        }
        ldlt.factorize(system_->K);
        if (ldlt.info() != Eigen::Success)
          throw NumericalFailure("LSMFM system matrix is singular",
                                 "load step " + std::to_string(step_) + ", iteration " +
                                     std::to_string(it),
                                 "every node needs integration points in its influence domain; "
                                 "raise LSMFM/Support ratio");
        dU = ldlt.solve(system_->F);
      }
    }
    // Line search on I along dU (eq. 39). The full step is taken when it decreases I enough
    // (Armijo, I'(0) = −2 F·dU < 0 for the Gauss–Newton direction). Otherwise I(α) is
    // minimised on [0, 1] by golden sections: I is only piecewise smooth (a point entering
    // the plastic range adds γ ∝ 1/K̄ to its residual), so a parabola through I(0), I'(0)
    // and I(1) — backtracking's model — can shrink the step to the yield surface only
    // geometrically (measured: 40 iterations at 0.9 per iteration on the finite extension,
    // E/K̄ = 3e5), while the line minimum lies just across it.
    const double slope = -2.0 * system_->F.dot(dU);
    const auto I_at = [&](double a) {
      for (unsigned int i = 0; i < n_unknowns_; ++i)
        trial[i] = U_[i] + a * dU[i];
      try {
        return evaluate(trial, false, nullptr);
      } catch (const NumericalFailure&) { // e.g. det f <= 0: outside the admissible range
        return std::numeric_limits<double>::infinity();
      }
    };
    double alpha = 1.0;
    if (!(I_at(1.0) <= I + 1e-4 * slope)) {
      const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
      double a = 0, b = 1, c = b - ratio * (b - a), d = a + ratio * (b - a);
      double fc = I_at(c), fd = I_at(d);
      for (unsigned int k = 0; k < 30 && b - a > 1e-6; ++k) {
        if (fc < fd) {
          b = d;
          d = c;
          fd = fc;
          c = b - ratio * (b - a);
          fc = I_at(c);
        } else {
          a = c;
          c = d;
          fc = fd;
          d = a + ratio * (b - a);
          fd = I_at(d);
        }
      }
      alpha = fc < fd ? c : d;
      if (!(std::min(fc, fd) < I)) {
        // At a kink of I (a point on the yield surface, iterate-wise switching) the
        // one-sided gradient need not vanish at the minimum: no decrease along the Newton
        // direction with the gradient already well down is that minimum.
        if (result.relative_gradient <= std::sqrt(prm_.tolerance))
          return;
        std::ostringstream what;
        what << "LSMFM line search found no decrease of I along the Newton direction (I = " << I
             << ", |grad I| at " << result.relative_gradient << " of its start)";
        throw NumericalFailure(
            what.str(), "load step " + std::to_string(step_) + ", iteration " + std::to_string(it),
            "take more load steps; check that the boundary conditions do not "
            "contradict each other");
      }
    }
    for (unsigned int i = 0; i < n_unknowns_; ++i)
      trial[i] = U_[i] + alpha * dU[i];
    result.min_line_search = std::min(result.min_line_search, alpha);
    // Largest update over the step's increment, for displacement and stress apart.
    double du[2] = {0, 0}, inc[2] = {0, 0};
    for (unsigned int i = 0; i < n_unknowns_; ++i) {
      const unsigned int kind = (i % block_) < dim ? 0 : 1;
      du[kind] = std::max(du[kind], std::abs(trial[i] - U_[i]));
      inc[kind] = std::max(inc[kind], std::abs(trial[i] - U_n_[i]));
    }
    last_update = 0;
    for (unsigned int kind = 0; kind < 2; ++kind)
      last_update = std::max(last_update, inc[kind] > 0 ? du[kind] / inc[kind] : 0.0);
    U_.swap(trial);
  }
}

template <int dim>
void LsmfmSolver<dim>::commit() {
  const bool finite = prm_.finite_strain();
  returned_.assign(points_.size(), ReturnMapped());
  constitutive_stress_.assign(finite ? points_.size() : 0, Voigt{});
  record_ = true;
  evaluate(U_, false, nullptr); // the final plastic set (and the return mappings)
  record_ = false;
  for (unsigned int q = 0; q < points_.size(); ++q) {
    PointState& st = state_[q];
    const Voigt sigma = point_stress(q);
    if (return_mapping_) {
      const auto& rm = returned_[q];
      // A point of a consistent plastic set has Δγ >= 0 up to the set's tolerance.
      flowed_[q] = rm.plastic && rm.delta_q > 0;
      if (flowed_[q]) {
        for (unsigned int a = 0; a < 6; ++a)
          st.ep[a] += rm.plastic_strain[a];
        st.q += rm.delta_q;
      }
    } else if (std::isfinite(mat_.yield_stress)) {
      const Voigt sb = project(sigma);
      double fnorm = 0;
      for (unsigned int a = 0; a < 6; ++a)
        fnorm += sigma[a] * sb[a];
      fnorm = std::sqrt(std::max(fnorm, 0.0));
      const double phi =
          fnorm - std::sqrt(2.0 / 3.0) * (mat_.yield_stress + mat_.hardening_modulus * st.q);
      flowed_[q] = plastic_set_[q] && phi > 0 && fnorm > 0;
      if (flowed_[q]) {
        const double gamma = 1.5 * phi / mat_.hardening_modulus; // eq. (41a)
        for (unsigned int a = 0; a < 6; ++a)
          st.ep[a] += gamma * sb[a] / fnorm;  // eq. (41b)
        st.q += std::sqrt(2.0 / 3.0) * gamma; // eq. (13)
      }
    }
    if (finite) {
      const Tensor3 Fn_inv = dealii::invert(st.F_n);
      const Tensor3 G =
          incremental_gradient(point_sites_[q], U_, Fn_inv, axisymmetric_ ? radius_n(q) : 1.0);
      st.F_n = (dealii::unit_symmetric_tensor<3>() + G) * st.F_n;
      st.sigma_n = constitutive_stress_[q];
    }
  }
  last_increment_.resize(n_unknowns_);
  for (unsigned int i = 0; i < n_unknowns_; ++i)
    last_increment_[i] = U_[i] - U_n_[i];
  U_n_ = U_;
}

template <int dim>
typename LsmfmSolver<dim>::Voigt LsmfmSolver<dim>::point_stress(unsigned int q) const {
  const Site& s = point_sites_[q];
  Voigt sigma{};
  for (unsigned int k = 0; k < s.nodes.size(); ++k)
    for (unsigned int a = 0; a < active_.size(); ++a)
      sigma[active_[a]] += mat_.youngs_modulus * s.value[k] * U_[s.nodes[k] * block_ + dim + a];
  return sigma;
}

template <int dim>
double LsmfmSolver<dim>::point_jacobian(unsigned int q) const {
  return dealii::determinant(state_[q].F_n);
}

template <int dim>
dealii::Tensor<2, 3> LsmfmSolver<dim>::point_deformation_gradient(unsigned int q) const {
  if (prm_.finite_strain())
    return state_[q].F_n;
  Tensor3 F = dealii::unit_symmetric_tensor<3>();
  const Site& s = point_sites_[q];
  for (unsigned int k = 0; k < s.nodes.size(); ++k)
    for (unsigned int i = 0; i < dim; ++i)
      for (unsigned int j = 0; j < dim; ++j)
        F[i][j] += U_[s.nodes[k] * block_ + i] * s.gradient[k][j];
  if (axisymmetric_)
    for (unsigned int k = 0; k < s.nodes.size(); ++k)
      F[2][2] += s.value[k] * U_[s.nodes[k] * block_] / points_[q][0];
  return F;
}

template <int dim>
dealii::Tensor<2, dim> LsmfmSolver<dim>::deformation_gradient(const dealii::Point<dim>& X) const {
  typename MlsApproximation<dim>::Values v;
  dealii::Tensor<2, dim> F = dealii::unit_symmetric_tensor<dim>();
  if (!mls_.evaluate(X, v))
    return F * std::numeric_limits<double>::quiet_NaN();
  for (unsigned int k = 0; k < v.nodes.size(); ++k)
    for (unsigned int i = 0; i < dim; ++i)
      for (unsigned int j = 0; j < dim; ++j)
        F[i][j] += v.gradient[k][j] * U_[v.nodes[k] * block_ + i];
  return F;
}

template <int dim>
dealii::Tensor<1, dim> LsmfmSolver<dim>::displacement(const dealii::Point<dim>& X) const {
  typename MlsApproximation<dim>::Values v;
  dealii::Tensor<1, dim> u;
  if (!mls_.evaluate(X, v))
    return u * std::numeric_limits<double>::quiet_NaN();
  for (unsigned int k = 0; k < v.nodes.size(); ++k)
    for (unsigned int i = 0; i < dim; ++i)
      u[i] += v.value[k] * U_[v.nodes[k] * block_ + i];
  return u;
}

template <int dim>
typename LsmfmSolver<dim>::Voigt LsmfmSolver<dim>::stress(const dealii::Point<dim>& X) const {
  typename MlsApproximation<dim>::Values v;
  Voigt sigma{};
  if (!mls_.evaluate(X, v)) {
    sigma.fill(std::numeric_limits<double>::quiet_NaN());
    return sigma;
  }
  for (unsigned int k = 0; k < v.nodes.size(); ++k)
    for (unsigned int a = 0; a < active_.size(); ++a)
      sigma[active_[a]] += mat_.youngs_modulus * v.value[k] * U_[v.nodes[k] * block_ + dim + a];
  return sigma;
}

template <int dim>
double LsmfmSolver<dim>::von_mises(const Voigt& s) {
  const Voigt sb = project(s);
  double f = 0;
  for (unsigned int a = 0; a < 6; ++a)
    f += s[a] * sb[a];
  return std::sqrt(1.5 * std::max(f, 0.0));
}

template class LsmfmSolver<2>;
template class LsmfmSolver<3>;

} // namespace spinesim::meshfree
