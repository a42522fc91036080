#ifndef SPINESIM_FEM_MECHANICS_PARAMETERS_H
#define SPINESIM_FEM_MECHANICS_PARAMETERS_H

// The "Mechanics" input section: discretisation, kinematics, time integration, Newton and
// linear-solver controls, explicit-step safety and damping, and the boundary conditions.
// MechanicsSolver<dim>::Parameters names this type.

#include "fem/boundary_conditions.h"

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::fem {

template <int dim>
struct MechanicsParameters {
  unsigned int fe_degree = 1;
  std::string kinematics = "small_strain";       // small_strain | finite_strain
  std::string time_integration = "quasi_static"; // quasi_static | explicit
  bool plane_stress = false;                     // 2-D small strain only
  std::string volumetric_locking = "none";       // none | bbar (mean dilatation) | fbar
  unsigned int load_steps = 1;
  double newton_tolerance = 1e-8;
  unsigned int max_newton_iterations = 25;
  unsigned int max_load_step_cuts = 6;
  std::string linear_solver = "cg"; // cg | gmres | direct
  double linear_tolerance = 1e-10;
  unsigned int max_linear_iterations = 1000;
  double cfl_safety_factor = 0.5;
  double mass_damping = 0.0; // [1/s]
  // Dynamic relaxation (quasi-static steps relaxed pseudo-dynamically): "scaled" fictitious
  // masses that put every cell at the common stable step, or the "lumped" real masses.
  std::string relaxation_masses = "scaled";
  double taylor_quinney = 0.9; // fraction of plastic work turned into heat [-]
  typename BoundaryConditions<dim>::Parameters boundary_conditions;

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

// Throws InvalidInput for a Volumetric locking value the other entries exclude (parse() and
// the solver's constructor call it).
template <int dim>
void check_volumetric_locking(const MechanicsParameters<dim>& parameters);

} // namespace spinesim::fem

#endif
