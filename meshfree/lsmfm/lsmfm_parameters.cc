#include "meshfree/lsmfm/lsmfm_parameters.h"

#include "base/exceptions.h"

#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

void LsmfmParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Support ratio", "1.5", Double(0.0),
                    "Influence radius over nodal spacing, h_J / spacing (Kwon & Youn 2005: 1.5; "
                    "1.2 .. 3) [-].");
  prm.declare_entry("Integration", "support", Selection("support|background_grid"),
                    "Integration of the least-squares functional: support (2^dim points in each "
                    "node's influence domain, eq. 100) or background_grid (Gauss points on the "
                    "cells of the geometry's mesh) [-].");
  prm.declare_entry("Integration ratio", "0.25", Double(0.0, 1.0),
                    "Support integration: distance of the points from their node over the "
                    "nodal spacing, r of eq. (100) [-].");
  prm.declare_entry("Grid points", "4", Integer(1, 8),
                    "Background-grid integration: Gauss points per direction and cell [-].");
  prm.declare_entry(
      "Flow rule residual", "complementary", Selection("complementary|return_mapping"),
      "Constitutive residual of the functional: complementary, the flow rule in the "
      "complementary form of Kwon & Youn (eqs. 17a, 53; γ = 3φ̃/(2K̄), needs K̄ > 0 and "
      "converges slowly when E/K̄ is large), or return_mapping, R_u = C σ_rm(e_trial) − C σ "
      "with the J2 radial return of fem/materials (same solution, no 1/K̄; plane strain and "
      "3-D) [-].");
  prm.declare_entry(
      "Stress rate", "truesdell", Selection("truesdell|jaumann_log"),
      "Finite strain: truesdell, the incrementally objective update of Kwon & Youn (eqs. 46, "
      "50-51), or jaumann_log, the rotation-neutralised update with logarithmic strain "
      "increments of Abaqus' hypoelastic J2 (needs Flow rule residual = return_mapping) [-].");
  prm.declare_entry("Penalty factor", "1e4", Double(0.0),
                    "Boundary-condition penalty over the mean diagonal of the system matrix "
                    "(Kwon & Youn: 1e4 .. 1e6) [-].");
  prm.declare_entry("Equilibrium length", "0", Double(0.0),
                    "Length ℓ weighting the equilibrium residual, I = ∫ |R_u|² + (ℓ/E)² |div σ|² "
                    "dΩ; 0 = the diagonal of the domain's bounding box [m].");
  prm.declare_entry("Tolerance", "1e-10", Double(0.0),
                    "Newton stops when the gradient of I falls below this fraction of its value "
                    "at the start of the load step [-].");
  prm.declare_entry("Update tolerance", "1e-5", Double(0.0),
                    "Newton also stops when its last update is below this fraction of the load "
                    "step's increment (displacement and stress each) with the gradient of I "
                    "down by 1e-4 [-].");
  prm.declare_entry("Max iterations", "40", Integer(1), "Newton iterations per load step [-].");
  prm.declare_entry("Yield tolerance", "5e-3", Double(0.0, 1.0),
                    "The plastic set of a load step is accepted when no point violates the "
                    "yield condition by more than this fraction of the initial yield stress: "
                    "a flowing point below the yield surface or an elastic one above it (the "
                    "current stress for the complementary form, the trial stress for "
                    "return_mapping) [-].");
  prm.declare_entry("Maximum condition number", "1e12", Double(1.0),
                    "Largest accepted condition number of the MLS moment matrix [-].");
}

void LsmfmParameters::parse(const dealii::ParameterHandler& prm) {
  support_ratio = prm.get_double("Support ratio");
  integration = prm.get("Integration");
  integration_ratio = prm.get_double("Integration ratio");
  grid_points = prm.get_integer("Grid points");
  flow_rule = prm.get("Flow rule residual");
  stress_rate = prm.get("Stress rate");
  penalty_factor = prm.get_double("Penalty factor");
  equilibrium_length = prm.get_double("Equilibrium length");
  tolerance = prm.get_double("Tolerance");
  update_tolerance = prm.get_double("Update tolerance");
  max_iterations = prm.get_integer("Max iterations");
  yield_tolerance = prm.get_double("Yield tolerance");
  max_condition_number = prm.get_double("Maximum condition number");
  validate();
}

void LsmfmParameters::validate() const {
  const auto number = [](double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  };
  // A linear basis needs dim + 1 nodes in every influence domain; below about 1.2 spacings a
  // regular lattice leaves points covered by too few.
  if (!(support_ratio >= 1.2 && support_ratio <= 3.0))
    throw InvalidInput("LSMFM/Support ratio", "= " + number(support_ratio), "1.2 .. 3 [-]");
  if (!(penalty_factor >= 1.0 && penalty_factor <= 1e9))
    throw InvalidInput("LSMFM/Penalty factor", "= " + number(penalty_factor),
                       "1 .. 1e9 (Kwon & Youn: 1e4 .. 1e6) [-]");
  if (!(tolerance > 0 && tolerance < 1))
    throw InvalidInput("LSMFM/Tolerance", "= " + number(tolerance), "0 < tol < 1 [-]");
  if (plane_model != "plane_strain" && plane_model != "plane_stress" &&
      plane_model != "axisymmetric")
    throw InvalidInput("LSMFM plane model", "'" + plane_model + "'",
                       "plane_strain, plane_stress or axisymmetric");
  if (kinematics == "finite_strain" && plane_model == "plane_stress")
    throw InvalidInput("Mechanics/Plane stress",
                       "plane_stress with Kinematics = finite_strain: the thickness change is not "
                       "an unknown of the formulation",
                       "plane strain for finite strain, or Mechanics/Kinematics = small_strain");
}

} // namespace spinesim::meshfree
