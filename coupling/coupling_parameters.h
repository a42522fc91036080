#ifndef SPINESIM_COUPLING_COUPLING_PARAMETERS_H
#define SPINESIM_COUPLING_COUPLING_PARAMETERS_H

// The "Coupling" section: how cells turn into particles, the ghost layer and interface fit
// that join the two models, and the quasi-static relaxation of both.

#include "meshfree/particle_method.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <functional>
#include <string>
#include <vector>

namespace spinesim::coupling {

template <int dim>
struct CouplingParameters {
  unsigned int particles_per_direction = 1; // particles per cell = this^dim
  double ghost_layer = 2.0;                 // ghost layer width [horizons]
  double interface_radius = 2.5;            // MLS support of interface nodes [spacings]
  // overlap: Dirichlet–Dirichlet overlap (patch test exact at any strain, not energy
  // conserving); energy: energy-conserving splice with a consistency correction (exact for
  // affine fields in the linear limit); coupling/energy_splice.h.
  std::string splice = "overlap";
  // fem: a ghost family's deformation gradient is the FEM's displacement gradient at the ghost
  // (overlap splice); family: the family's own, as for free particles; auto: NOSB-PD ghosts
  // whose family reaches another law take the FEM's, SPG keeps the family's.
  std::string ghost_gradient = "auto";
  double time_step_safety = 0.8; // PD stable step factor [-]
  bool all_particles = false;
  std::vector<double> region_lower, region_upper; // particles from t = 0 (empty = none)
  double principal_strain_threshold = 0;          // [-], 0 = off
  double plastic_strain_threshold = 0;            // [-], 0 = off
  double min_jacobian_ratio = 0;                  // [-], 0 = off
  double min_time_step = 0;                       // [s], 0 = off
  double buffer = 0;                              // converted around flagged cells [m]
  double support_clearance = 0; // no conversion within this of a supported point [m]
  std::vector<double> convert_lower, convert_upper; // cells the criteria may convert (empty = all)
  // Cells of these material ids stay FEM whatever the criteria say: set by scenarios whose
  // bodies hold an implant meshed with the bone (its cells never turn into bone particles).
  std::vector<unsigned int> unconverted_material_ids;
  // The implant's surface for contact with the particles (implant_contact.h): the signed
  // distance of a point in the implant's reference frame, negative inside [m], and the outward
  // normal at the nearest surface point. Set by scenarios that know the implant's true shape
  // (the cells only stair-step it); none = no contact.
  std::function<double(const dealii::Point<dim>&, dealii::Tensor<1, dim>&)> implant_surface;
  double implant_contact_stiffness = 2; // penalty, in E V / h^2 of the particle [-]; 0 = off
  double implant_friction = 0.3;        // Coulomb coefficient, particles on the implant [-]
  // Whether free particles start bonded to the implant's ghosts (a bonded, osseointegrated
  // interface whose bonds break by the bone's criteria), or meet it by contact alone (a
  // loosened implant: those bonds start broken).
  bool implant_bonded = true;
  unsigned int check_interval = 10;               // steps between conversion checks
  bool damage = true;                             // bonds may break (Effects/Damage)
  std::vector<double> refine_lower, refine_upper; // box refined before the run [m]
  unsigned int region_refinements = 0;
  double fracture_heat_fraction = 1.0; // share of broken-bond energy returned as heat [-]
  bool conserve_kinetic_energy = true; // scale the velocity fluctuation at conversion
  double relaxation_tolerance = 1e-6;  // quasi-static: free residual / reaction scale [-]
  unsigned int relaxation_max_iterations = 200000; // quasi-static: per step [-]
  unsigned int relaxation_report_interval = 5000;  // pseudo-steps between progress lines [-]
  unsigned int relaxation_step_cuts = 6; // quasi-static: halvings of a step that does not converge
  // Quasi-static with damage: bonds break only at the relaxation's equilibrium, which relaxes
  // again at the same load while any breaks (at most relaxation_breaking_passes times).
  bool relaxation_breaks_at_equilibrium = false;
  unsigned int relaxation_breaking_passes = 100;
  // The particle method (Effects/Particles method), its parameters read from its subsection
  // of "Coupling"; made in CouplingState::prepare() with the material of the FEM cells.
  std::string particles_method = "bond_based";
  meshfree::ParticleMethodMaker<dim> make_method;
  std::vector<std::vector<double>> cracks; // flattened corners per pre-crack [m]
  // A hole the FEM mesh does not model (a disc; 3-D: a cylinder along hole_axis): no particle
  // is made inside it, and the cells it reaches are particles from t = 0. Radius 0 = none.
  dealii::Point<dim> hole_centre;
  dealii::Tensor<1, dim> hole_axis; // unit vector (3-D)
  double hole_radius = 0;           // [m]
  bool has_hole() const { return hole_radius > 0; }
  // Distance from the hole's centre (2-D) or axis (3-D) [m].
  double distance_from_hole_axis(const dealii::Point<dim>& x) const;
  bool in_hole(const dealii::Point<dim>& x) const {
    return has_hole() && distance_from_hole_axis(x) < hole_radius;
  }

  static void declare(dealii::ParameterHandler& prm);
  // `particles_method` is the registered name the scene chose (Effects/Particles method).
  void parse(dealii::ParameterHandler& prm, const std::string& particles_method);
};

} // namespace spinesim::coupling

#endif
