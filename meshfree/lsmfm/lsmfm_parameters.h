#ifndef SPINESIM_MESHFREE_LSMFM_LSMFM_PARAMETERS_H
#define SPINESIM_MESHFREE_LSMFM_LSMFM_PARAMETERS_H

// The parameters of the least-squares meshfree solver (meshfree/lsmfm/lsmfm_solver.h), the
// same in 2-D and 3-D. Defaults are the values of Kwon & Youn (2005): influence radius 1.5
// nodal spacings (section 2), support integration with r = 0.25 (eq. 100), penalty 1e4..1e6
// times the mean diagonal (section 5.1).

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::meshfree {

struct LsmfmParameters {
  double support_ratio = 1.5;          // h_J / nodal spacing (α of eq. 100) [-]
  std::string integration = "support"; // support|background_grid
  double integration_ratio = 0.25;     // r of eq. (100) [-]
  unsigned int grid_points = 4;        // Gauss points per direction and cell [-]
  // Set by the caller from its Mechanics section, not declared here:
  std::string plane_model = "plane_strain"; // plane_strain|plane_stress|axisymmetric (2-D)
  std::string kinematics = "small_strain";  // small_strain|finite_strain
  std::string flow_rule = "complementary";  // complementary|return_mapping
  std::string stress_rate = "truesdell";    // truesdell|jaumann_log (finite strain)
  double penalty_factor = 1e4;              // α over the mean diagonal [-]
  double equilibrium_length = 0;            // ℓ weighting div σ [m]; 0 = domain diagonal
  double tolerance = 1e-10;                 // on the gradient of I, relative to the step's first
  double update_tolerance = 1e-5;           // on the Newton update over the step's increment
  unsigned int max_iterations = 40;         // Newton iterations per load step
  double yield_tolerance = 5e-3;            // plastic set consistent to this fraction of σ_Y
  double max_condition_number = 1e12;       // MLS moment matrix guard [-]

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
  // InvalidInput naming the entry.
  void validate() const;
  bool finite_strain() const { return kinematics == "finite_strain"; }
};

} // namespace spinesim::meshfree

#endif
