#ifndef SPINESIM_MESHFREE_SPG_SPG_PARAMETERS_H
#define SPINESIM_MESHFREE_SPG_SPG_PARAMETERS_H

// The parameters of the SPG solver (meshfree/spg/spg_solver.h), the same in 2-D and 3-D
// (SPGSolver<dim>::Parameters).

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::meshfree {

// The reference configuration of the kernels: total Lagrangian, updated Lagrangian (periodic
// reset) or adaptive Lagrangian (chain rule, reset on deformation; Wu, Park & Chen 2015).
enum class SpgKernelUpdate { total_lagrangian, updated_lagrangian, adaptive_lagrangian };

struct SpgParameters {
  std::string kernel = "cubic_bspline";    // cubic_bspline|quartic
  std::string support_shape = "spherical"; // spherical|cubic
  double dilation = 1.5;                   // a / h [-], 1.1 .. 2.5
  double max_condition_number = 1e10;      // RK moment matrix guard [-]
  double stabilisation = 0.1;              // η [-], 0 = plain DNI
  unsigned int smoothing_interval = 1;     // [steps]
  std::string kernel_update = "total_lagrangian";
  unsigned int reset_interval = 50;    // [steps] (updated_lagrangian)
  double adaptive_threshold = 0.2;     // max |F_rel − I| before a reset (adaptive) [-]
  double cfl = 0.4;                    // [-]
  double critical_plastic_strain = 0;  // ε_crit [-], 0 = off
  double critical_stretch = 0;         // s_crit [-], 0 = off
  double contact_penalty_factor = 1.0; // k_c / (ρ c_p² h^(dim−2)) [-]
  double contact_offset = 0.0;         // contact distance / h [-]

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
  // InvalidInput naming the entry.
  void validate() const;
  SpgKernelUpdate update_mode() const;
};

// x as the SPG messages print it (the stream's default format, e.g. "0.01", "1e-05").
std::string spg_number(double x);

} // namespace spinesim::meshfree

#endif
