// The `spg_patch_test` validation scenario: RK shape functions with a linear basis reproduce a
// linear displacement field exactly on an IRREGULAR (jittered) particle set. The RK
// coefficients are set to the linear field d_J = A X_J + b; the physical displacement
// u^h(X_I) = Σ_J Ψ_J(X_I) d_J and the nodal deformation gradient must equal A X_I + b and
// I + A to round-off, and the displacement-smoothing stabilisation must exert no force.
// The essential-boundary transformation is checked too: the boundary particles are
// constrained to the linear field while the interior coefficients are perturbed.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/spg/spg_solver.h"

#include <deal.II/base/utilities.h>

#include <cmath>
#include <random>

namespace spinesim::applications {

using namespace framework;

namespace {

struct PatchParameters {
  double size = 1.0, spacing = 0.1, jitter = 0.3;
  unsigned int seed = 1;
  std::vector<double> gradient, translation;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Size", "1.0", Double(0.0), "Edge length of the square/cube patch [m].");
    prm.declare_entry("Particle spacing", "0.1", Double(0.0), "Lattice spacing before jitter [m].");
    prm.declare_entry("Jitter", "0.3", Double(0.0, 0.45),
                      "Random offset of every particle per direction, over the spacing [-].");
    prm.declare_entry("Seed", "1", Integer(0), "Random seed of the jitter [-].");
    prm.declare_entry(
        "Displacement gradient", "0.01, -0.004, 0.003, 0.02, 0.005, -0.002, 0.001, 0.004, -0.01",
        List(Double()), "Row-major A of u = A X + b; the first dim² values are used [-].");
    prm.declare_entry("Translation", "1e-3, -2e-3, 5e-4", List(Double()),
                      "b of u = A X + b; the first dim values are used [m].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    size = prm.get_double("Size");
    spacing = prm.get_double("Particle spacing");
    jitter = prm.get_double("Jitter");
    seed = prm.get_integer("Seed");
    gradient =
        parse_number_list(prm.get("Displacement gradient"), "SPG patch test/Displacement gradient");
    translation = parse_number_list(prm.get("Translation"), "SPG patch test/Translation");
    if (!(spacing > 0 && spacing <= 0.25 * size))
      throw InvalidInput("SPG patch test/Particle spacing", "= " + std::to_string(spacing),
                         "0 < h <= Size/4 [m]");
  }
};

template <int dim>
class PatchTest : public Scenario {
 public:
  explicit PatchTest(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Material", law_);
    parse_section(prm, "SPG", spg_);
    parse_section(prm, "SPG patch test", patch_);
    if (patch_.gradient.size() < dim * dim || patch_.translation.size() < dim)
      throw InvalidInput("SPG patch test/Displacement gradient",
                         "too few values for dimension " + std::to_string(dim),
                         "dim² gradient and dim translation values");
  }

  void run(RunContext& ctx) override {
    const auto law = materials::create_law(law_);
    dealii::Point<dim> lo, hi;
    for (unsigned int d = 0; d < dim; ++d)
      hi[d] = patch_.size;
    const double h = patch_.spacing;
    auto lattice = meshfree::ParticleSet<dim>::lattice(lo, hi, h);
    std::mt19937 gen(patch_.seed);
    std::uniform_real_distribution<double> jit(-patch_.jitter * h, patch_.jitter * h);
    std::vector<dealii::Point<dim>> pts;
    std::vector<double> vol;
    for (unsigned int i = 0; i < lattice.size(); ++i) {
      auto x = lattice.reference_position(i);
      for (unsigned int d = 0; d < dim; ++d)
        x[d] += jit(gen);
      pts.push_back(x);
      vol.push_back(lattice.volume(i));
    }
    auto p = meshfree::ParticleSet<dim>::from_points(pts, vol);
    p.set_density(law->density());
    dealii::Tensor<2, dim> A;
    dealii::Tensor<1, dim> b;
    for (unsigned int i = 0; i < dim; ++i) {
      b[i] = patch_.translation[i];
      for (unsigned int j = 0; j < dim; ++j)
        A[i][j] = patch_.gradient[i * dim + j];
    }
    const auto exact = [&](const dealii::Point<dim>& X) { return A * X + b; };

    // 1. Reproduction of the linear field.
    meshfree::SPGSolver<dim> spg(spg_, *law, p, h);
    double u_scale = 0;
    for (unsigned int i = 0; i < p.size(); ++i) {
      p.displacement(i) = exact(p.reference_position(i));
      u_scale = std::max(u_scale, p.displacement(i).norm());
    }
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "spg");
      spg.compute_forces(p);
    }
    double u_err = 0, F_err = 0;
    for (unsigned int i = 0; i < p.size(); ++i) {
      u_err = std::max(u_err,
                       (spg.physical_displacements()[i] - exact(p.reference_position(i))).norm());
      auto e = spg.deformation_gradients()[i] - A;
      for (unsigned int d = 0; d < dim; ++d)
        e[d][d] -= 1.0;
      F_err = std::max(F_err, e.norm());
    }
    // Stabilisation force of the linear field, relative to the stiffness scale κ|u|.
    const double kappa =
        spg_.stabilisation * law->youngs_modulus() * vol[0] / std::pow(spg.support_size(), 2);
    const double stab_res = spg.max_smoothing_residual();

    // 2. Transformation method: boundary particles constrained to the field, interior
    // coefficients perturbed; u^h at the boundary must still be exact.
    meshfree::SPGSolver<dim> spg2(spg_, *law, p, h);
    std::vector<unsigned int> boundary;
    for (unsigned int i = 0; i < p.size(); ++i) {
      const auto& X = p.reference_position(i);
      bool on = false;
      for (unsigned int d = 0; d < dim; ++d)
        on = on || X[d] < 0.75 * h || X[d] > patch_.size - 0.75 * h;
      if (on) {
        boundary.push_back(i);
        for (unsigned int d = 0; d < dim; ++d)
          spg2.constrain(p, i, d, exact(X)[d]);
      }
      for (unsigned int d = 0; d < dim; ++d)
        p.displacement(i)[d] += 0.1 * u_scale * jit(gen) / h;
    }
    spg2.compute_forces(p);
    double bc_err = 0;
    for (unsigned int i : boundary)
      bc_err = std::max(bc_err,
                        (spg2.physical_displacements()[i] - exact(p.reference_position(i))).norm());

    const double rel = u_err / u_scale;
    auto& s = ctx.summary();
    s.set_figure("max_displacement_error", rel, "-");
    s.set_figure("max_gradient_error", F_err / A.norm(), "-");
    s.set_figure("max_smoothing_residual", stab_res / u_scale, "-");
    s.set_figure("max_stabilisation_force_scale", kappa * stab_res, "N");
    s.set_figure("boundary_constraint_error", bc_err / u_scale, "-");
    s.set_figure("particles", p.size(), "-");
    s.set_figure("boundary_particles", boundary.size(), "-");
    double max_cond = 0;
    for (double c : spg.shape_functions().condition_number)
      max_cond = std::max(max_cond, c);
    s.set_figure("max_moment_condition_number", max_cond, "-");
    ctx.history().add({{"particles", double(p.size())},
                       {"max_displacement_error", rel},
                       {"max_gradient_error", F_err / A.norm()},
                       {"boundary_constraint_error", bc_err / u_scale}});
    ctx.flush_history();
    ctx.log() << "  " << p.size() << " jittered particles: displacement error " << rel
              << ", gradient error " << F_err / A.norm() << ", boundary error " << bc_err / u_scale
              << "\n";
  }

 private:
  materials::LawParameters law_;
  meshfree::SpgParameters spg_;
  PatchParameters patch_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(spg_patch_test, "spg_patch_test",
                           "SPG linear patch test on jittered particles: reproduction of a "
                           "linear displacement field and of its gradient, essential boundary.",
                           "particles:spg", create_for_dimension<PatchTest>, sections::material(),
                           sections::spg(), {"SPG patch test", PatchParameters::declare})

} // namespace spinesim::applications
