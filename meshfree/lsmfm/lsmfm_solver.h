#ifndef SPINESIM_MESHFREE_LSMFM_LSMFM_SOLVER_H
#define SPINESIM_MESHFREE_LSMFM_LSMFM_SOLVER_H

// The least-squares meshfree method for elasto-plasticity of Kwon & Youn (2005, KSME A 29(6)).
//
// Unknowns: MLS coefficients of the displacement u and of the stress σ at every node
// (eq. 34). The first-order least-squares functional (eq. 18)
//     I(u, σ) = ∫ R_uᵀR_u + (ℓ/E)² R_σᵀR_σ dΩ + α_u Σ_A (u-condition)² + α_t Σ_A (t-condition)²
// is minimised in each load step by Newton (eqs. 20–33: Gauss–Newton, here with the flow
// direction's curvature added when that keeps the matrix positive definite) with a line
// search on I (eq. 39). Residuals (LSMFM/Flow rule residual = complementary, the paper's):
//   small strain (eq. 17):   R_u = B_e u − e^p_n − C σ − γ ∂f/∂σ,   R_σ = div σ;
//   finite strain (eq. 53):  R_u = ε̃ − C σ + (1/J̃) C (f σ_n fᵀ) − γ ∂f/∂σ, with the
//     incremental deformation f = ∂x^{n+1}/∂x^n, J̃ = det f and ε̃ = ½(I − f⁻ᵀf⁻¹) (eq. 46):
//     the incrementally objective Truesdell-rate update of eq. (51).
// J2 with linear isotropic hardening (eq. 12): f = |s|, φ̃ = f − √(2/3)(σ_Y + K̄ q_n) at the
// current stress; γ = 3φ̃/(2K̄) at plastic points (eq. 41a), 0 elsewhere — the hardening law
// and the yield condition hold exactly at every integration point, the flow rule and
// equilibrium in the least-squares sense; the tangent of R_u in σ is Σ of eq. (27), so K̄ > 0.
// With Flow rule residual = return_mapping, R_u = C σ_rm(e_trial) − C σ instead (the J2 radial
// return of fem/materials on the trial elastic strain; the same solution, no 1/K̄), and in
// finite strain Stress rate = jaumann_log replaces eq. (51) by the rotation-neutralised update
// with logarithmic strain increments. Which points are plastic is held fixed during a Newton
// solve and updated between solves (solve_step() says why).
//
// Departures from the paper, each stated where it is made:
//  * the equilibrium residual carries the weight (ℓ/E)², which makes both residuals
//    dimensionless (the paper works in consistent units with unit weights);
//  * finite strain: R_u is linearised exactly in the nodal increments through
//    f = I + ∂ũ/∂x^n, instead of the configuration freeze of eq. (57) and the operators
//    B_e1..B_e4 of eqs. (58–65); both give the same converged state, the exact one converges
//    faster. div σ is taken in the configuration of the current iterate, as eq. (57) does,
//    and differentiated there too (the paper freezes it), so Newton's gradient is I's;
//  * stress in 2-D: plane strain keeps σ_zz as an unknown (ε_zz = 0 is a row of R_u);
//    plane stress drops σ_zz and the zz row of R_u (ε_zz is then free, so that row holds
//    identically).
// Boundary conditions are the paper's penalty collocation at boundary nodes (eqs. 69, 86)
// with fixed directions: d·u(x_A) = ū (d a unit vector) and d·(σ n)(x_A) = t̄ with n the
// outward normal, carried by the deformation (n ∝ F_n⁻ᵀN) in finite strain. The curvature
// terms of eqs. (74–83), which move the directions with the boundary, are not needed there.
// A traction condition may instead hold its normal fixed in space (a flat rigid tool's
// contact face: the friction traction on a platen).
//
// Axisymmetric (2-D, LsmfmParameters::plane_model = axisymmetric, set by the caller, as Kwon &
// Youn's ring compression, section 6.3): x = (r, z), the hoop direction θ is the third one. σ_θθ is
// an unknown like plane strain's σ_zz; the hoop strain is u_r/r (small strain) and the incremental
// hoop stretch f_θθ = r_{n+1}/r_n (finite strain); the equilibrium residual gains the hoop terms of
// div σ in cylindrical coordinates, (σ_rr − σ_θθ)/r and σ_rz/r, at the current radius; the
// functional is integrated over the ring volume (weights × 2πr). Every node and integration point
// must lie at r > 0: a body touching the axis (a solid cylinder) is refused, its 1/r terms are
// singular there.

#include "fem/materials/isotropic_hardening.h"
#include "meshfree/lsmfm/lsmfm_parameters.h"
#include "meshfree/lsmfm/mls_approximation.h"

#include <deal.II/base/point.h>
#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <array>
#include <memory>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class LsmfmSolver {
 public:
  // Linear elasticity with J2 plasticity and linear isotropic hardening (eq. 12). A yield
  // stress of +inf makes the solid purely elastic.
  struct Material {
    double youngs_modulus = 0;    // E [Pa]
    double poisson_ratio = 0;     // ν [-]
    double yield_stress = 0;      // σ_Y [Pa]
    double hardening_modulus = 0; // K̄ [Pa], > 0 when σ_Y is finite
  };

  // d·u(x_A) = value [m] at node A (d: unit vector).
  struct DisplacementCondition {
    unsigned int node;
    dealii::Tensor<1, dim> direction;
    double value;
  };
  // d·(σ n)(x_A) = value [Pa] at node A, n the outward unit normal in the reference
  // configuration, d a unit vector.
  struct TractionCondition {
    unsigned int node;
    dealii::Tensor<1, dim> normal, direction;
    double value;
    // The normal is the current (spatial) one as given, not carried by the deformation.
    bool spatial_normal = false;
    // A spring on the boundary (Robin condition): d·(σ n) + stiffness d·u = value, stiffness
    // [Pa/m] >= 0 (0: a plain traction condition). Regularised friction holds a contact node
    // this way: t = −k (u − u_0).
    double stiffness = 0;
  };

  // Voigt order of the stress and the engineering strain: 11, 22, 33, 12, 23, 13.
  using Voigt = std::array<double, 6>;

  struct StepResult {
    unsigned int iterations = 0;
    double functional = 0;        // I at the converged state [m^dim]
    double relative_gradient = 0; // |∇I| over its value at the start of the step
    unsigned int plastic_points = 0;
    double min_line_search = 1;     // smallest accepted line-search factor of the step
    unsigned int set_updates = 0;   // Newton solves repeated for a changed plastic set
    unsigned int kink_stops = 0;    // solves ended as a stall at a kink of I (see newton())
    double max_yield_violation = 0; // of the accepted plastic set [Pa] (see solve_step())
    unsigned int set_fallbacks = 0; // set iterations ended by the iterate-wise solve
  };

  // nodes: x_J [m]; spacing: nodal spacing per node [m] (h_J = support ratio × spacing);
  // points, weights: the integration points and weights of I [m, m^dim].
  LsmfmSolver(const LsmfmParameters& parameters, const Material& material,
              std::vector<dealii::Point<dim>> nodes, const std::vector<double>& spacing,
              std::vector<dealii::Point<dim>> points, std::vector<double> weights);
  ~LsmfmSolver();

  // The boundary conditions (their values are those of the next step). Changing the node
  // lists rebuilds the matrix pattern (contact that comes and goes); keeping them is cheaper.
  void set_conditions(std::vector<DisplacementCondition> displacement,
                      std::vector<TractionCondition> traction);

  // One load step: Newton to convergence, then the plastic state is committed.
  // NumericalFailure (with the point and a hint) if Newton fails or a value is not finite.
  StepResult solve_step();
  // The same in two parts, for conditions that depend on the solution (contact and friction):
  // solve_trial() solves the load step and leaves it open; called again (after new
  // set_conditions) it solves the same step from the last trial; accept_step() commits it.
  StepResult solve_trial();
  // A trial that throws closes the step: the next solve_step/solve_trial starts it again from
  // the last accepted state.
  void accept_step();

  // Results.
  unsigned int n_nodes() const { return mls_.nodes().size(); }
  unsigned int n_points() const { return points_.size(); }
  unsigned int n_unknowns() const { return n_unknowns_; }
  const MlsApproximation<dim>& approximation() const { return mls_; }
  // Total displacement u^h(X) and stress σ^h(X) [Pa] at a reference point (MLS evaluation).
  dealii::Tensor<1, dim> displacement(const dealii::Point<dim>& X) const;
  Voigt stress(const dealii::Point<dim>& X) const;
  // Total deformation gradient I + ∇u^h at a reference point (in-plane part in 2-D).
  dealii::Tensor<2, dim> deformation_gradient(const dealii::Point<dim>& X) const;
  bool axisymmetric() const { return axisymmetric_; }
  // At integration point q: reference position, weight, Cauchy stress [Pa], effective plastic
  // strain q, current deformation gradient determinant.
  const dealii::Point<dim>& point(unsigned int q) const { return points_[q]; }
  // Axisymmetric: the weight includes 2πr (a volume of the ring).
  double weight(unsigned int q) const { return weights_[q]; }
  Voigt point_stress(unsigned int q) const;
  double point_plastic_strain(unsigned int q) const { return state_[q].q; }
  double point_jacobian(unsigned int q) const;
  // Deformation gradient at integration point q: I + ∇u (small strain; 2-D embedded in 3×3
  // with F_zz = 1, axisymmetric F_θθ = 1 + u_r/r) or the committed F_n (finite strain).
  dealii::Tensor<2, 3> point_deformation_gradient(unsigned int q) const;
  // Von Mises stress of a Voigt stress [Pa].
  static double von_mises(const Voigt& s);

 private:
  struct PointState {
    Voigt ep{};               // engineering plastic strain e^p_n (small strain)
    double q = 0;             // effective plastic strain q_n
    Voigt sigma_n{};          // Cauchy stress at t_n [Pa] (finite strain)
    dealii::Tensor<2, 3> F_n; // deformation gradient at t_n (finite strain)
  };
  struct Site { // where residuals are evaluated
    std::vector<unsigned int> nodes;
    std::vector<double> value;
    std::vector<dealii::Tensor<1, dim>> gradient; // reference gradients
    std::vector<unsigned int> pair_offset;        // value offsets in the matrix, per node pair
  };
  class LinearSystem;
  struct ReturnMapped {
    Voigt stress{};            // σ_rm [Pa]
    Voigt plastic_strain{};    // Δe^p, engineering [-]
    double tangent[6][6] = {}; // dσ_a/de_b, e the engineering trial strain [Pa]
    double delta_q = 0;        // Δq [-]
    bool plastic = false;
  };

  LsmfmParameters prm_;
  Material mat_;
  MlsApproximation<dim> mls_;
  std::vector<dealii::Point<dim>> points_;
  std::vector<double> weights_;
  std::vector<PointState> state_;
  std::vector<Site> point_sites_;
  std::vector<DisplacementCondition> u_conditions_;
  std::vector<TractionCondition> t_conditions_;
  std::vector<Site> node_sites_;     // at every node (boundary collocation and output)
  std::vector<unsigned int> active_; // active Voigt components of σ and rows of R_u
  unsigned int block_ = 0;           // unknowns per node: dim + active_.size()
  unsigned int n_unknowns_ = 0;
  double ell_ = 0;                     // equilibrium length ℓ [m]
  double alpha_u_ = -1, alpha_t_ = -1; // penalties (set at the first assembly)
  std::vector<double> U_, U_n_;        // unknowns: per node [u (m), σ/E (-)]
  std::vector<double> last_increment_; // U_n − U_{n−1}: the predictor of the next step
  std::unique_ptr<LinearSystem> system_;
  unsigned int step_ = 0;
  bool open_step_ = false;    // solve_trial() ran, accept_step() not yet
  bool axisymmetric_ = false; // 2-D (r, z) with the hoop direction third
  bool second_order_ = true;  // assemble the Newton Hessian (else Gauss–Newton)
  bool return_mapping_ = false;
  bool jaumann_log_ = false;       // finite strain: Jaumann-type update with log strain increments
  bool record_ = false;            // evaluate() stores the return mappings and the plastic set
  bool iterate_switching_ = false; // plastic set from the current stress at every iterate
  std::vector<ReturnMapped> returned_;
  // Finite strain, per point, recorded by evaluate() in commit(): the stress of the
  // constitutive update (σ_rm, or the complementary form's σ^h + D R_u), which the next step
  // starts from as σ_n. Starting from the least-squares fit σ^h instead would leave each
  // step's constitutive residual out of every later step: the result then drifts with the
  // number of load steps (a stuck block at 0.125 % compression lost 10 % of its load from 1 to
  // 160 steps).
  std::vector<Voigt> constitutive_stress_;
  std::unique_ptr<materials::IsotropicHardening> hardening_;
  std::vector<char> plastic_set_;    // per point: flows in the current Newton solve
  std::vector<double> trial_excess_; // q_tr − σ_y,n at the last evaluation [Pa]
  std::vector<char> flowed_;         // per point: flowed in the last committed step

  Site make_site(const dealii::Point<dim>& x, const std::string& what) const;
  void build_pattern();
  // I at the unknowns U; with `assemble` also the Gauss–Newton matrix and the right-hand side
  // −Jᵀr. Counts plastic points.
  double evaluate(const std::vector<double>& U, bool assemble, unsigned int* plastic);
  void commit();
  // J2 radial return of a trial elastic strain (engineering Voigt) at effective plastic
  // strain q (fem/materials/j2_return_mapping.h); Hooke's law when σ_Y is infinite.
  // branch: 0 decides (fem/materials' radial return), 1 elastic, 2 the plastic branch
  // continued to Δγ < 0 (within a Newton solve on a fixed plastic set).
  ReturnMapped return_map(const Voigt& trial_strain, double q, int branch) const;
  // Newton on I with the plastic set fixed; result: iterations, I, gradient (over g0).
  void newton(StepResult& result, double g0);
  StepResult trial(); // solve_trial() without its clean-up on failure
  // G = ∂ũ/∂x^n at a site; axisymmetric: G_θθ = ũ_r / r_n with r_n the radius at t_n.
  dealii::Tensor<2, 3> incremental_gradient(const Site& s, const std::vector<double>& U,
                                            const dealii::Tensor<2, 3>& F_n_inverse,
                                            double r_n) const;
  // The radius of integration point q at t_n (axisymmetric) [m].
  double radius_n(unsigned int q) const;
};

} // namespace spinesim::meshfree

#endif
