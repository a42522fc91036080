#include "coupling/coupling_parameters.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <cmath>

namespace spinesim::coupling {

using namespace dealii;

namespace {

std::vector<double> parse_doubles(const std::string& list, const std::string& where) {
  return parse_number_list(list, where, /*allow_empty=*/true);
}

// A box is given by both corners or by neither.
template <int dim>
void check_box_corners(const std::vector<double>& lower, const std::vector<double>& upper,
                       const std::string& where) {
  if (lower.size() != upper.size() || (!lower.empty() && lower.size() < dim))
    throw InvalidInput(where, "the two corners need " + std::to_string(dim) + " coordinates each",
                       "both empty, or both 'x,y" + std::string(dim == 3 ? ",z" : "") + "' [m]");
}

} // namespace

template <int dim>
void CouplingParameters<dim>::declare(ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Particles per cell direction", "1", Integer(1, 3),
                    "Particles per converted cell and direction (1, 2^dim or 3^dim per cell, at "
                    "sub-cell centres) [-].");
  prm.declare_entry("Ghost layer", "2", Double(1),
                    "Width of the FEM-driven ghost particle layer around the free particles, in "
                    "horizons; 2 gives every ghost bonded to a free particle a complete horizon "
                    "for the surface correction [-].");
  prm.declare_entry("Interface radius", "2.5", Double(1.5),
                    "Support radius of the moving-least-squares fit that drives interface FEM "
                    "nodes from the free particles, in particle spacings [-].");
  prm.declare_entry(
      "Implant contact stiffness", "2", Double(0),
      "Penalty of the contact between particles and an implant's true surface (a pedicle "
      "screw's threads), in units of the particle's E V / h^2 (E h in 3-D: a cube of bone of "
      "side h under a face load). A particle touches the surface at half a spacing; the penalty "
      "stands in for that half cube, whose own stiffness is 2 (the default): higher values make "
      "the contact stiffer than the bone it replaces. 0 = no contact [-].");
  prm.declare_entry("Implant interface", "bonded", Selection("bonded|contact"),
                    "How bone particles meet an implant [-]. bonded: they start bonded to it "
                    "(an osseointegrated interface; the bonds break by the bone's criteria, and "
                    "contact with the implant's surface, Effects/Contact, keeps failed bone out "
                    "of it); contact: by contact alone, their bonds to it start broken (a "
                    "loosened implant; needs Effects/Contact).");
  prm.declare_entry("Implant friction coefficient", "0.3", Double(0),
                    "Coulomb friction coefficient between the particles and an implant's "
                    "surface [-].");
  prm.declare_entry(
      "Splice", "overlap", Selection("overlap|energy"),
      "How the FEM and the particles join [-]. overlap: ghost particles driven by the FEM and "
      "interface nodes driven by a moving-least-squares fit of the particles; exact for affine "
      "fields at any strain, but not energy-conserving: some modes grow slowly in long explicit "
      "runs (docs/coupling.md, stability of the splice). energy: the same layers, forces "
      "passed back through the transposes of both maps, so explicit steps conserve an energy; "
      "a symmetric low-rank correction makes affine fields exact in the linear (small-strain) "
      "limit.");
  prm.declare_entry(
      "Ghost gradient", "auto", Selection("auto|fem|family"),
      "Deformation gradient at which a ghost particle's family (SPG: row) is evaluated, overlap "
      "splice [-]. fem: the FEM's displacement gradient at the ghost (with its B-bar or F-bar "
      "modification), so the ghosts carry the FEM's own stress into the particle zone, also where "
      "a ghost's family reaches across a change of material (a stiff cap, cortical shell or "
      "implant beside soft particles); exact for affine fields like the family's. family: the "
      "gradient of the ghost's family, as for a free particle; where that family mixes a stiff "
      "and a soft material, the stiff law at the mixed gradient puts on the particles a stress "
      "the FEM does not have, and the overlap splice never hands it to the FEM "
      "(docs/coupling.md, the splice across a change of material). auto: NOSB-PD ghosts whose "
      "family reaches a particle of another law take the FEM's gradient, the others keep their "
      "family's (so a body of one material runs as with family); SPG keeps the family's, as its "
      "free coefficients take much of their stiffness from the ghost rows: with fem a small "
      "converted cluster of the vertebra diverged. The energy splice takes its forces from its "
      "energy and always uses the family's gradient.");
  prm.declare_entry("Time step safety", "0.8", Double(0, 1),
                    "Factor on the PD stable time step (Silling & Askari 2005) [-].");
  prm.declare_entry("All particles", "false", Bool(),
                    "Convert every cell at t = 0: the same scene run fully in particles [-].");
  prm.declare_entry("Initial region lower corner", "", Anything(),
                    "Lower corner of a box whose cells are particles from t = 0; empty = none "
                    "[m].");
  prm.declare_entry("Initial region upper corner", "", Anything(), "Upper corner of that box [m].");
  prm.declare_entry("Principal strain threshold", "0", Double(0),
                    "Convert cells whose maximum principal strain reaches this (e.g. a fraction "
                    "of the PD critical stretch); 0 = off [-].");
  prm.declare_entry("Plastic strain threshold", "0", Double(0),
                    "Convert cells whose equivalent plastic strain reaches this; 0 = off [-].");
  prm.declare_entry("Minimum Jacobian ratio", "0", Double(0, 1),
                    "Convert cells whose deformed min/max det J falls below this (distorted or "
                    "inverted elements); 0 = off [-].");
  prm.declare_entry("Minimum time step", "0", Double(0),
                    "Convert cells whose stable explicit step falls below this; 0 = off [s].");
  prm.declare_entry("Buffer", "0", Double(0),
                    "Cells whose centre lies within this distance of a flagged cell convert "
                    "with it, so the particle zone runs ahead of a crack [m].");
  prm.declare_entry(
      "Support clearance", "0", Double(0),
      "Cells whose centre lies within this distance of a point a Dirichlet condition of "
      "Mechanics holds (a vertex or the centre of a face on its boundary id, a vertex inside "
      "its region) never convert, nor does the buffer reach them. The overlap splice "
      "drives the FEM's interface DoFs by the particles and the ghosts by the FEM (Dirichlet on "
      "both sides): between the particles and a support it needs FEM DoFs that are neither "
      "(e.g. the bone cells next to a platen's cap); without them the reaction at that "
      "support measures the interface fit, not the load. 0 = off [m].");
  prm.declare_entry("Conversion region lower corner", "", Anything(),
                    "Lower corner of the box whose cells the criteria may convert (by cell "
                    "centre; the buffer reaches no farther); empty = anywhere on the particle "
                    "lattice [m].");
  prm.declare_entry("Conversion region upper corner", "", Anything(),
                    "Upper corner of that box [m].");
  prm.declare_entry("Check interval", "10", Integer(1),
                    "Explicit steps between conversion checks [-].");
  prm.declare_entry("Refinement region lower corner", "", Anything(),
                    "Lower corner of a box refined before the run, where particles will "
                    "appear (particles take the spacing of the finest cells); empty = none [m].");
  prm.declare_entry("Refinement region upper corner", "", Anything(),
                    "Upper corner of that box [m].");
  prm.declare_entry("Region refinements", "0", Integer(0, 8),
                    "Times the cells in the refinement box are bisected [-].");
  prm.declare_entry("Fracture heat fraction", "1", Double(0, 1),
                    "With Heat: share of the elastic energy a bond holds when it breaks that "
                    "returns to the FEM heat equation as a source in the particle's host cell "
                    "(the rest leaves as surface energy and sound) [-].");
  prm.declare_entry("Conserve kinetic energy", "true", Bool(),
                    "At conversion, scale each cell's interpolated velocity fluctuation about "
                    "its mean so that the particles carry the kinetic energy the cell's nodes "
                    "lose (with more than one particle per cell). The lumped nodal energy of a "
                    "linear velocity field is that of its values at the nodes, so the particles "
                    "take a steeper profile inside the cell (scale 2 for an affine field with 2 "
                    "particles per direction); false keeps the interpolated velocities (mass and "
                    "momentum still exact) and logs the energy defect [-].");
  prm.declare_entry("Relaxation tolerance", "1e-6", Double(0),
                    "Quasi-static coupled runs (Mechanics/Time integration = quasi_static), and "
                    "a softening CT model past its peak without particles: dynamic relaxation "
                    "of each step ends when the free residual (FEM DoFs and particles) is this "
                    "fraction of the larger of the reactions and the largest residual of the "
                    "step [-].");
  prm.declare_entry("Relaxation max iterations", "200000", Integer(1),
                    "Quasi-static coupled runs: pseudo-time steps allowed per step before the "
                    "run stops as not converged [-].");
  prm.declare_entry("Relaxation step cuts", "6", Integer(0, 30),
                    "Quasi-static coupled runs: how often a load step whose relaxation does not "
                    "converge within Relaxation max iterations is cut. The state at the start of "
                    "the step is restored (conversions and broken bonds included) and the load "
                    "is applied in two halves, each cut again if needed: up to 2^cuts sub-steps "
                    "[-]. After two converged sub-steps the sub-step doubles again, up to the "
                    "step. 0 = the run stops at the first relaxation that does not converge.");
  prm.declare_entry("Break bonds", "while relaxing", Selection("while relaxing|at equilibrium"),
                    "Quasi-static coupled runs with Effects/Damage: when the particles' bonds "
                    "break. while relaxing: as the relaxation's pseudo-dynamics stretch them, so "
                    "its transient (which depends on the damping and the pseudo-masses) may "
                    "break bonds the equilibrium would keep; at equilibrium: the step relaxes "
                    "with every bond held, the bonds the converged state stretches past their "
                    "criterion break, and the step relaxes again at the same load until none "
                    "breaks (at most Breaking passes; each relaxation has its own Relaxation "
                    "max iterations) [-].");
  prm.declare_entry("Breaking passes", "100", Integer(1),
                    "Quasi-static coupled runs with Break bonds = at equilibrium: relaxations "
                    "of one load step while bonds keep breaking; a step whose bonds still break "
                    "after these is cut like one that does not converge [-].");
  prm.declare_entry("Relaxation report interval", "5000", Integer(0),
                    "Quasi-static coupled runs: every this many pseudo-steps of a step's "
                    "relaxation, a line in the log with the relative residual, the damping and "
                    "the stiffness estimate behind it, the free particles and the cells "
                    "converted so far; 0 = none [-].");
  prm.declare_entry("Hole centre", "", Anything(),
                    "Centre of a hole the FEM mesh does not model (a plate's hole, a pilot "
                    "hole): no particle is made inside it, and the cells it reaches (within half "
                    "a cell diagonal) are particles from t = 0, so the hole is a free surface of "
                    "the particle zone at the lattice's resolution. A disc in 2-D, a cylinder "
                    "along Hole axis in 3-D; empty = no hole [m].");
  prm.declare_entry("Hole radius", "0", Double(0), "Radius of that hole; 0 = no hole [m].");
  prm.declare_entry("Hole axis", "0, 0, 1", Anything(),
                    "3-D: direction of the hole's axis (any length; ignored in 2-D) [-].");
  // One subsection per registered particle method ("Bond based", "NOSB", ...).
  meshfree::declare_particle_method_sections(prm);
  for (unsigned int k = 1; k <= 4; ++k) {
    prm.enter_subsection("Crack " + std::to_string(k));
    prm.declare_entry("Corners", "", Anything(),
                      "Pre-crack corners 'x,y; x,y' (2-D segment) or four corners (3-D "
                      "quadrilateral); bonds crossing it start broken; empty = unused [m].");
    prm.leave_subsection();
  }
}

template <int dim>
void CouplingParameters<dim>::parse(ParameterHandler& prm, const std::string& method) {
  particles_per_direction = prm.get_integer("Particles per cell direction");
  ghost_layer = prm.get_double("Ghost layer");
  interface_radius = prm.get_double("Interface radius");
  implant_contact_stiffness = prm.get_double("Implant contact stiffness");
  implant_friction = prm.get_double("Implant friction coefficient");
  implant_bonded = prm.get("Implant interface") == "bonded";
  splice = prm.get("Splice");
  ghost_gradient = prm.get("Ghost gradient");
  time_step_safety = prm.get_double("Time step safety");
  all_particles = prm.get_bool("All particles");
  region_lower =
      parse_doubles(prm.get("Initial region lower corner"), "Coupling/Initial region lower corner");
  region_upper =
      parse_doubles(prm.get("Initial region upper corner"), "Coupling/Initial region upper corner");
  check_box_corners<dim>(region_lower, region_upper, "Coupling/Initial region lower corner");
  principal_strain_threshold = prm.get_double("Principal strain threshold");
  plastic_strain_threshold = prm.get_double("Plastic strain threshold");
  min_jacobian_ratio = prm.get_double("Minimum Jacobian ratio");
  min_time_step = prm.get_double("Minimum time step");
  buffer = prm.get_double("Buffer");
  support_clearance = prm.get_double("Support clearance");
  check_interval = prm.get_integer("Check interval");
  convert_lower = parse_doubles(prm.get("Conversion region lower corner"),
                                "Coupling/Conversion region lower corner");
  convert_upper = parse_doubles(prm.get("Conversion region upper corner"),
                                "Coupling/Conversion region upper corner");
  check_box_corners<dim>(convert_lower, convert_upper, "Coupling/Conversion region lower corner");
  refine_lower = parse_doubles(prm.get("Refinement region lower corner"),
                               "Coupling/Refinement region lower corner");
  refine_upper = parse_doubles(prm.get("Refinement region upper corner"),
                               "Coupling/Refinement region upper corner");
  region_refinements = prm.get_integer("Region refinements");
  fracture_heat_fraction = prm.get_double("Fracture heat fraction");
  conserve_kinetic_energy = prm.get_bool("Conserve kinetic energy");
  relaxation_tolerance = prm.get_double("Relaxation tolerance");
  relaxation_max_iterations = prm.get_integer("Relaxation max iterations");
  relaxation_report_interval = prm.get_integer("Relaxation report interval");
  relaxation_step_cuts = prm.get_integer("Relaxation step cuts");
  relaxation_breaks_at_equilibrium = prm.get("Break bonds") == "at equilibrium";
  relaxation_breaking_passes = prm.get_integer("Breaking passes");
  check_box_corners<dim>(refine_lower, refine_upper, "Coupling/Refinement region lower corner");
  const auto centre = parse_doubles(prm.get("Hole centre"), "Coupling/Hole centre");
  hole_radius = prm.get_double("Hole radius");
  if (centre.empty() != (hole_radius == 0) || (!centre.empty() && centre.size() != dim))
    throw InvalidInput("Coupling/Hole centre",
                       "a hole needs a centre of " + std::to_string(dim) +
                           " coordinates and a radius above 0 (centre '" + prm.get("Hole centre") +
                           "', radius " + prm.get("Hole radius") + ")",
                       "both unset (no hole), or 'x,y" + std::string(dim == 3 ? ",z" : "") +
                           "' [m] with Hole radius > 0 [m]");
  for (unsigned int d = 0; d < centre.size(); ++d)
    hole_centre[d] = centre[d];
  hole_axis = Tensor<1, dim>();
  if (dim == 3 && has_hole()) {
    const auto axis = parse_doubles(prm.get("Hole axis"), "Coupling/Hole axis");
    double norm = 0;
    for (const double a : axis)
      norm += a * a;
    norm = std::sqrt(norm);
    if (axis.size() != 3 || !(norm > 0) || !std::isfinite(norm))
      throw InvalidInput("Coupling/Hole axis", "'" + prm.get("Hole axis") + "' is not a direction",
                         "three numbers, not all zero, e.g. '0, 0, 1' [-]");
    for (unsigned int d = 0; d < dim; ++d)
      hole_axis[d] = axis[d] / norm;
  }
  particles_method = method;
  make_method = meshfree::particle_method_maker<dim>(method, prm, "Effects/Particles method");
  cracks.clear();
  for (unsigned int k = 1; k <= 4; ++k) {
    prm.enter_subsection("Crack " + std::to_string(k));
    const std::string corners = prm.get("Corners");
    prm.leave_subsection();
    if (corners.empty())
      continue;
    cracks.push_back(
        parse_crack_corners(corners, "Coupling/Crack " + std::to_string(k) + "/Corners", dim));
  }
}

template <int dim>
double CouplingParameters<dim>::distance_from_hole_axis(const Point<dim>& x) const {
  Tensor<1, dim> r = x - hole_centre;
  if (dim == 3)
    r -= (r * hole_axis) * hole_axis;
  return r.norm();
}

template struct CouplingParameters<2>;
template struct CouplingParameters<3>;

} // namespace spinesim::coupling
