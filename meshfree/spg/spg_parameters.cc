#include "meshfree/spg/spg_parameters.h"

#include "base/exceptions.h"
#include "meshfree/spg/rk_kernel.h"

#include <sstream>

namespace spinesim::meshfree {

std::string spg_number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

void SpgParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Kernel", "cubic_bspline", Selection(RKKernel<2>::type_names()),
                    "RK kernel: cubic_bspline (SPG) or quartic (1 − r²)^4 [-].");
  prm.declare_entry(
      "Support shape", "spherical", Selection(RKKernel<2>::support_names()),
      "Kernel support: spherical (|z| < a) or cubic (tensor product, |z_k| < a) [-].");
  prm.declare_entry("Dilation", "1.5", Double(0.0),
                    "Support size over particle spacing a/h, 1.1 .. 2.5 [-].");
  prm.declare_entry("Maximum condition number", "1e10", Double(1.0),
                    "Largest accepted condition number of the RK moment matrix [-].");
  prm.declare_entry("Stabilisation", "0.1", Double(0.0),
                    "Displacement-smoothing stabilisation parameter eta (0 = plain nodal "
                    "integration; 0.05 .. 0.5 recommended) [-].");
  prm.declare_entry("Smoothing interval", "1", Integer(1),
                    "Re-evaluate the smoothing (stabilisation) force every n steps [steps].");
  prm.declare_entry("Kernel update", "total_lagrangian",
                    Selection("total_lagrangian|updated_lagrangian|adaptive_lagrangian"),
                    "Kernel reference: total_lagrangian, updated_lagrangian (periodic reset) "
                    "or adaptive_lagrangian (chain rule, reset on deformation) [-].");
  prm.declare_entry("Reset interval", "50", Integer(1),
                    "Steps between reference resets (updated_lagrangian) [steps].");
  prm.declare_entry("Adaptive threshold", "0.2", Double(0.0),
                    "Reset when max |F_rel − I| exceeds this (adaptive_lagrangian) [-].");
  prm.declare_entry("CFL", "0.4", Double(0.0),
                    "Courant number of the stable step dt = CFL h sigma_min / c_p [-].");
  prm.declare_entry("Critical plastic strain", "0", Double(0.0),
                    "Bond breaks when the mean effective plastic strain of its ends exceeds "
                    "this (0 = off) [-].");
  prm.declare_entry("Critical stretch", "0", Double(0.0),
                    "Bond breaks when its stretch exceeds this (0 = off) [-].");
  prm.declare_entry("Contact penalty factor", "1", Double(0.0),
                    "Contact penalty over the particle stiffness rho c_p^2 h^(dim-2) [-].");
  prm.declare_entry("Contact offset", "0", Double(0.0),
                    "Contact distance from the particle centre over the spacing [-].");
}

void SpgParameters::parse(const dealii::ParameterHandler& prm) {
  kernel = prm.get("Kernel");
  support_shape = prm.get("Support shape");
  dilation = prm.get_double("Dilation");
  max_condition_number = prm.get_double("Maximum condition number");
  stabilisation = prm.get_double("Stabilisation");
  smoothing_interval = prm.get_integer("Smoothing interval");
  kernel_update = prm.get("Kernel update");
  reset_interval = prm.get_integer("Reset interval");
  adaptive_threshold = prm.get_double("Adaptive threshold");
  cfl = prm.get_double("CFL");
  critical_plastic_strain = prm.get_double("Critical plastic strain");
  critical_stretch = prm.get_double("Critical stretch");
  contact_penalty_factor = prm.get_double("Contact penalty factor");
  contact_offset = prm.get_double("Contact offset");
  validate();
}

void SpgParameters::validate() const {
  RKKernel<2>::from_names(kernel, support_shape); // the same names in 2-D and 3-D
  if (!(dilation >= 1.1 && dilation <= 2.5))
    throw InvalidInput("Dilation", "= " + spg_number(dilation),
                       "1.1 .. 2.5 (support over spacing)");
  if (!(stabilisation >= 0.0 && stabilisation <= 10.0))
    throw InvalidInput("Stabilisation", "= " + spg_number(stabilisation),
                       "0 .. 10 (0.05 .. 0.5 usual)");
  if (smoothing_interval < 1)
    throw InvalidInput("Smoothing interval", "= 0", ">= 1 [steps]");
  update_mode();
  if (reset_interval < 1)
    throw InvalidInput("Reset interval", "= 0", ">= 1 [steps]");
  if (!(adaptive_threshold > 0.0))
    throw InvalidInput("Adaptive threshold", "= " + spg_number(adaptive_threshold), "> 0");
  if (!(cfl > 0.0 && cfl <= 1.0))
    throw InvalidInput("CFL", "= " + spg_number(cfl), "0 < CFL <= 1");
  if (!(critical_plastic_strain >= 0.0) || !(critical_stretch >= 0.0))
    throw InvalidInput("Critical plastic strain / Critical stretch", "negative", ">= 0 (0 = off)");
  if (!(contact_penalty_factor >= 0.0 && contact_penalty_factor <= 100.0))
    throw InvalidInput("Contact penalty factor", "= " + spg_number(contact_penalty_factor),
                       "0 .. 100");
  if (!(contact_offset >= 0.0 && contact_offset <= 1.0))
    throw InvalidInput("Contact offset", "= " + spg_number(contact_offset), "0 .. 1");
  if (!(max_condition_number > 1.0))
    throw InvalidInput("Maximum condition number", "= " + spg_number(max_condition_number), "> 1");
}

SpgKernelUpdate SpgParameters::update_mode() const {
  if (kernel_update == "total_lagrangian")
    return SpgKernelUpdate::total_lagrangian;
  if (kernel_update == "updated_lagrangian")
    return SpgKernelUpdate::updated_lagrangian;
  if (kernel_update == "adaptive_lagrangian")
    return SpgKernelUpdate::adaptive_lagrangian;
  throw InvalidInput("Kernel update", "'" + kernel_update + "'",
                     "total_lagrangian|updated_lagrangian|adaptive_lagrangian");
}

} // namespace spinesim::meshfree
