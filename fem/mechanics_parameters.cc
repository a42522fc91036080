#include "fem/mechanics_parameters.h"

#include "base/exceptions.h"

namespace spinesim::fem {

using namespace dealii;

template <int dim>
void MechanicsParameters<dim>::declare(ParameterHandler& prm) {
  prm.declare_entry("Finite element degree", "1", Patterns::Integer(1, 2),
                    "Polynomial degree of the Lagrange displacement element (1 or 2) [-].");
  prm.declare_entry("Kinematics", "small_strain", Patterns::Selection("small_strain|finite_strain"),
                    "Linearised strain or total-Lagrangian finite strain [-].");
  prm.declare_entry("Plane stress", "false", Patterns::Bool(),
                    "2-D only, small strain: sigma_zz = 0 instead of plane strain [-].");
  prm.declare_entry(
      "Volumetric locking", "none", Patterns::Selection("none|bbar|fbar"),
      "Treatment of volumetric locking [-]: none (standard displacement element); bbar "
      "(B-bar by mean dilatation, Hughes 1980: every quadrature point of a cell takes the "
      "cell-average volumetric strain, the deviatoric strain stays point-wise; small strain); "
      "or fbar (F-bar, de Souza Neto et al. 1996: F scaled to the cell's mean volume change; "
      "finite strain, explicit steps only, as it has no Newton tangent). Switch it on for nearly "
      "incompressible materials (Poisson ratio above about "
      "0.45, e.g. soft tissue, or J2 plastic flow), where the standard Q1 element is far too "
      "stiff. Plane strain or 3-D only.");
  prm.declare_entry("Time integration", "quasi_static",
                    Patterns::Selection("quasi_static|explicit"),
                    "Implicit quasi-static Newton or explicit central differences [-].");
  prm.declare_entry("Load steps", "1", Patterns::Integer(1),
                    "Load increments per quasi-static solve [-].");
  prm.declare_entry("Newton tolerance", "1e-8", Patterns::Double(0),
                    "Relative residual (or displacement increment) for convergence [-].");
  prm.declare_entry("Max Newton iterations", "25", Patterns::Integer(1),
                    "Newton iterations before the load step is cut [-].");
  prm.declare_entry("Max load step cuts", "6", Patterns::Integer(0),
                    "Halvings of the load increment before giving up [-].");
  prm.declare_entry("Linear solver", "cg", Patterns::Selection("cg|gmres|direct"),
                    "CG or GMRES with algebraic multigrid, or a direct solver [-].");
  prm.declare_entry("Linear tolerance", "1e-10", Patterns::Double(0),
                    "Linear residual reduction relative to the right-hand side [-].");
  prm.declare_entry("Max linear iterations", "1000", Patterns::Integer(1),
                    "Iterative solver limit [-].");
  prm.declare_entry("CFL safety factor", "0.5", Patterns::Double(0, 1),
                    "Fraction of the CFL stable step used by the explicit integrator, and by "
                    "dynamic relaxation, whose scaled masses (Relaxation masses) put every cell "
                    "at this fraction of its own step [-].");
  prm.declare_entry("Mass damping", "0", Patterns::Double(0),
                    "Mass-proportional damping coefficient alpha [1/s].");
  prm.declare_entry(
      "Relaxation masses", "scaled", Patterns::Selection("scaled|lumped"),
      "Masses of dynamic relaxation, where a quasi-static step is relaxed pseudo-dynamically "
      "(coupled FEM/particle runs; a softening solid past its peak) [-]. scaled: each cell's "
      "share of the lumped mass times (dt / dt_cell)^2, so that every cell (and every particle) "
      "runs at the one stable step dt, as fictitious densities do (Underwood 1983; Kilic & "
      "Madenci 2010); the equilibrium is the same, reached in fewer pseudo-steps where cell "
      "sizes, moduli or densities vary. lumped: the real lumped masses at the stable step.");
  prm.declare_entry("Taylor-Quinney coefficient", "0.9", Patterns::Double(0, 1),
                    "Fraction beta of the plastic work turned into heat when Heat and Mechanics "
                    "are both on (plastic-work heating; 0 switches it off) [-]. 0.9 is the "
                    "classical value for metals (Taylor & Quinney, Proc. R. Soc. A 143 (1934) "
                    "307); measured 0.6-1 depending on strain and rate.");
  prm.enter_subsection("Boundary conditions");
  BoundaryConditions<dim>::Parameters::declare(prm);
  prm.leave_subsection();
}

template <int dim>
void MechanicsParameters<dim>::parse(const ParameterHandler& prm) {
  fe_degree = prm.get_integer("Finite element degree");
  kinematics = prm.get("Kinematics");
  plane_stress = prm.get_bool("Plane stress");
  volumetric_locking = prm.get("Volumetric locking");
  time_integration = prm.get("Time integration");
  load_steps = prm.get_integer("Load steps");
  newton_tolerance = prm.get_double("Newton tolerance");
  max_newton_iterations = prm.get_integer("Max Newton iterations");
  max_load_step_cuts = prm.get_integer("Max load step cuts");
  linear_solver = prm.get("Linear solver");
  linear_tolerance = prm.get_double("Linear tolerance");
  max_linear_iterations = prm.get_integer("Max linear iterations");
  cfl_safety_factor = prm.get_double("CFL safety factor");
  mass_damping = prm.get_double("Mass damping");
  relaxation_masses = prm.get("Relaxation masses");
  taylor_quinney = prm.get_double("Taylor-Quinney coefficient");
  if (!(taylor_quinney >= 0 && taylor_quinney <= 1))
    throw InvalidInput("Taylor-Quinney coefficient", "must lie in [0, 1]", "0 <= beta <= 1");
  if (!(newton_tolerance > 0))
    throw InvalidInput("Newton tolerance", "must be positive", "a value in (0, 1)");
  if (!(linear_tolerance > 0))
    throw InvalidInput("Linear tolerance", "must be positive", "a value in (0, 1)");
  if (!(cfl_safety_factor > 0))
    throw InvalidInput("CFL safety factor", "must be positive", "a value in (0, 1]");
  if (plane_stress && dim != 2)
    throw InvalidInput("Plane stress", "plane stress needs a 2-D model", "false in 3-D");
  if (plane_stress && kinematics != "small_strain")
    throw InvalidInput("Plane stress", "plane stress is only implemented for small strain",
                       "false, or Kinematics = small_strain");
  check_volumetric_locking(*this);
  // prm is const, so the boundary slots are read by path below the current subsection.
  boundary_conditions.parse(prm, {"Boundary conditions"});
}

template <int dim>
void check_volumetric_locking(const MechanicsParameters<dim>& p) {
  if (p.volumetric_locking != "none" && p.volumetric_locking != "bbar" &&
      p.volumetric_locking != "fbar")
    throw InvalidInput("Volumetric locking", "unknown '" + p.volumetric_locking + "'",
                       "none|bbar|fbar");
  if (p.volumetric_locking == "bbar" && p.kinematics != "small_strain")
    throw InvalidInput("Volumetric locking",
                       "bbar is the small-strain mean dilatation; Kinematics = " + p.kinematics,
                       "fbar with Kinematics = finite_strain (explicit steps), or bbar with "
                       "Kinematics = small_strain");
  if (p.volumetric_locking == "fbar" && p.kinematics != "finite_strain")
    throw InvalidInput("Volumetric locking",
                       "fbar scales the deformation gradient; Kinematics = " + p.kinematics,
                       "bbar with Kinematics = small_strain, or fbar with Kinematics = "
                       "finite_strain");
  if (p.volumetric_locking != "none" && p.plane_stress)
    throw InvalidInput("Volumetric locking",
                       "plane stress does not lock (the out-of-plane strain is free), and " +
                           p.volumetric_locking + " replaces the volume change of plane strain",
                       "none with Plane stress = true");
}

template struct MechanicsParameters<2>;
template struct MechanicsParameters<3>;
template void check_volumetric_locking(const MechanicsParameters<2>&);
template void check_volumetric_locking(const MechanicsParameters<3>&);

} // namespace spinesim::fem
