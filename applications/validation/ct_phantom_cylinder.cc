// The `ct_phantom_cylinder` validation scenario: the CT pipeline end to end on a synthetic
// phantom with a known answer. The scenario writes a CT volume itself (a cylinder of uniform
// density in air, on a rotated, anisotropic grid) into the run directory as a MetaImage, NRRD
// or NIfTI file, reads it back through the normal reader, calibrates, meshes it (threshold
// mode), assigns per-cell density-mapped moduli (MechanicsSolver::set_cell_laws) and
// compresses it between frictionless platens: end faces z- held axially (id 4), z+ displaced
// axially (id 5), one end face at the axis pinned in x, y against rigid motion (id 6).
// A uniform bar in uniaxial stress has stiffness K = E A / L. The reference uses the
// voxelised cross-section actually meshed, A = V_mesh / L (every voxel column spans the
// whole length), so stiffness_relative_error measures reader, calibration, density map, law,
// per-cell laws and the solver; the voxelisation of the circle is reported separately
// (area_relative_error, stiffness_relative_error_exact_area against pi r^2).

#include "applications/common_sections.h"
#include "applications/ct/ct_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/ct/ct_cell_laws.h"
#include "fem/ct/ct_model.h"
#include "fem/ct/ct_volume.h"
#include "fem/ct/density_modulus_law.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct PhantomParameters {
  double radius = 5e-3;                                   // [m]
  double length = 20e-3;                                  // [m]
  std::vector<double> voxel_size{0.5e-3, 0.5e-3, 0.8e-3}; // [m]
  std::vector<double> origin{0, 0, 0};                    // [m]
  double rotation = 30;                                   // [deg] image axes about z
  double density = 300;                                   // [mg/cm^3]
  double background = -5;                                 // [mg/cm^3] air
  std::string value_type = "density";                     // density | hu
  double intercept = 0, slope = 1e-3;                     // rho = a + b HU [g/cm^3]
  std::string format = "mha";
  unsigned int coarsening = 1;
  unsigned int refinements = 0;
  double strain = 1e-3; // [-] axial compressive strain

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Radius", "5", Double(0), "Cylinder radius [mm].");
    prm.declare_entry("Length", "20", Double(0),
                      "Cylinder length along the image's third axis, rounded to whole slices "
                      "[mm].");
    prm.declare_entry("Voxel size", "0.5, 0.5, 0.8", List(Double(0), 3, 3),
                      "Voxel edge lengths along the three image axes [mm].");
    prm.declare_entry("Origin", "10, -5, 3", List(Double(), 3, 3),
                      "Physical position of the centre of voxel (0,0,0) [mm].");
    prm.declare_entry("Rotation", "30", Double(-180, 180),
                      "Rotation of the image axes about z (direction matrix) [deg].");
    prm.declare_entry("Density", "300", Double(0),
                      "Uniform equivalent mineral density of the cylinder [mg/cm^3].");
    prm.declare_entry("Background density", "-5", Double(),
                      "Density of the air around the cylinder [mg/cm^3].");
    prm.declare_entry("Value type", "density", Selection("density|hu"),
                      "Voxel values written: density [mg/cm^3] or HU through the calibration "
                      "below (read back through the same calibration) [-].");
    prm.declare_entry("Calibration intercept", "-0.02", Double(),
                      "rho = intercept + slope * HU (Value type = hu) [g/cm^3].");
    prm.declare_entry("Calibration slope", "0.0008", Double(0),
                      "rho = intercept + slope * HU (Value type = hu) [g/cm^3 per HU].");
    prm.declare_entry("File format", "mha", Selection("mha|mhd|nrrd|nii|nii.gz"),
                      "Format of the synthetic volume written to the run directory [-].");
    prm.declare_entry("Coarsening factor", "1", Integer(1, 8),
                      "Voxels per cell edge of the mesh [-].");
    prm.declare_entry("Global refinements", "0", Integer(0, 3),
                      "Uniform refinements of the voxel mesh (children keep their coarse "
                      "cell's law) [-].");
    prm.declare_entry("Axial strain", "0.001", Double(0, 0.05),
                      "Compressive strain imposed by the upper platen, delta / L [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    const auto mm = [&](const std::string& name) {
      std::vector<double> v = parse_number_list(prm.get(name), "Phantom/" + name);
      for (auto& x : v)
        x *= 1e-3;
      return v;
    };
    radius = 1e-3 * prm.get_double("Radius");
    length = 1e-3 * prm.get_double("Length");
    voxel_size = mm("Voxel size");
    origin = mm("Origin");
    rotation = prm.get_double("Rotation");
    density = prm.get_double("Density");
    background = prm.get_double("Background density");
    value_type = prm.get("Value type");
    intercept = prm.get_double("Calibration intercept");
    slope = prm.get_double("Calibration slope");
    format = prm.get("File format");
    coarsening = prm.get_integer("Coarsening factor");
    refinements = prm.get_integer("Global refinements");
    strain = prm.get_double("Axial strain");
    if (!(density > 2 * std::max(background, 0.0)))
      throw InvalidInput("Phantom/Density", std::to_string(density),
                         "a density above twice the background (threshold at half of it)");
    if (radius < 2 * std::max(voxel_size[0], voxel_size[1]))
      throw InvalidInput("Phantom/Radius", std::to_string(radius * 1e3) + " mm",
                         "at least two voxels");
    if (!(strain > 0))
      throw InvalidInput("Phantom/Axial strain", "0", "a positive compressive strain");
  }
};

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

class CtPhantomCylinder : public Scenario {
 public:
  explicit CtPhantomCylinder(const ScenarioFactoryArgs& args) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3 (CT volumes are 3-D)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Phantom", phantom_);
    parse_section(prm, "Bone", bone_);
    parse_section(prm, "Mechanics", mech_);
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions", "the scenario applies its own platens",
                         "no Dirichlet slots here");
  }

  void run(RunContext& ctx) override {
    const PhantomParameters& ph = phantom_;
    // 1. The synthetic volume: axis through the image centre along the third axis.
    fem::CtVolume volume;
    const unsigned int margin = 2;
    const unsigned int nr_x = std::ceil(ph.radius / ph.voxel_size[0]);
    const unsigned int nr_y = std::ceil(ph.radius / ph.voxel_size[1]);
    volume.size = {{2 * (nr_x + margin), 2 * (nr_y + margin),
                    std::max(1u, unsigned(std::lround(ph.length / ph.voxel_size[2])))}};
    volume.spacing = {{ph.voxel_size[0], ph.voxel_size[1], ph.voxel_size[2]}};
    volume.origin = {{ph.origin[0], ph.origin[1], ph.origin[2]}};
    const double a = ph.rotation * M_PI / 180, c = std::cos(a), s = std::sin(a);
    volume.direction = {{{{c, -s, 0}}, {{s, c, 0}}, {{0, 0, 1}}}};
    const double ic = 0.5 * (volume.size[0] - 1), jc = 0.5 * (volume.size[1] - 1);
    const double rho = ph.density * 1e-3;  // [g/cm^3]
    auto stored = [&](double mg_per_cm3) { // what the file holds for a density
      return ph.value_type == "hu" ? (mg_per_cm3 * 1e-3 - ph.intercept) / ph.slope : mg_per_cm3;
    };
    volume.values.resize(volume.n_voxels());
    std::size_t inside = 0;
    for (unsigned int k = 0; k < volume.size[2]; ++k)
      for (unsigned int j = 0; j < volume.size[1]; ++j)
        for (unsigned int i = 0; i < volume.size[0]; ++i) {
          const double dx = (i - ic) * ph.voxel_size[0], dy = (j - jc) * ph.voxel_size[1];
          const bool in = dx * dx + dy * dy <= ph.radius * ph.radius;
          inside += in;
          volume.values[volume.linear_index(i, j, k)] = stored(in ? ph.density : ph.background);
        }
    const std::string file = (ctx.output().path() / ("phantom." + ph.format)).string();
    if (ctx.is_root())
      fem::write_ct_volume(volume, file);
    MPI_Barrier(ctx.comm());
    const double L = volume.size[2] * ph.voxel_size[2];
    ctx.log() << "  phantom: " << volume.size[0] << " x " << volume.size[1] << " x "
              << volume.size[2] << " voxels, " << inside / volume.size[2]
              << " per slice in the cylinder, written to " << file << "\n";

    // 2. Read back and mesh through the normal path.
    fem::CtParameters p = bone_.law;
    p.image_file = file;
    p.value_type = ph.value_type;
    p.calibration_intercept = ph.intercept;
    p.calibration_slope = ph.slope;
    p.labels.clear();
    p.density_threshold = 0.5 * rho;
    p.coarsening_factor = ph.coarsening;
    p.mark_end_faces = true;
    dealii::parallel::distributed::Triangulation<3> tria(ctx.comm());
    fem::CtModel model;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "ct model");
      model = fem::build_ct_model(p, tria);
    }
    ctx.log() << "  " << model.summary() << "\n";
    for (const auto& warning : model.warnings)
      ctx.warn(warning);
    // Pin (id 6): the lower end face nearest the axis, x and y held.
    const dealii::Point<3> axis = volume.point(ic, jc, 0);
    double best = std::numeric_limits<double>::max();
    dealii::Triangulation<3>::face_iterator pin;
    for (const auto& cell : tria.cell_iterators_on_level(0))
      for (const unsigned int f : cell->face_indices())
        if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == 4) {
          const auto x = cell->face(f)->center();
          const double d = std::hypot(x[0] - axis[0], x[1] - axis[1]);
          if (d < best - 1e-12 * L) {
            best = d;
            pin = cell->face(f);
          }
        }
    if (best == std::numeric_limits<double>::max())
      throw InvalidInput("Phantom", "no lower end face found", "a cylinder spanning the image");
    pin->set_all_boundary_ids(6);
    if (ph.refinements > 0)
      tria.refine_global(ph.refinements);

    // 3. Per-cell laws and the platens.
    const fem::CtCellLaws laws(model, ct::cell_law_options(bone_, nullptr, false));
    fem::MechanicsSolver<3> solver(tria, mech_);
    solver.set_cell_laws(laws.function());
    const double delta = ph.strain * L;
    auto& bc = solver.boundary_conditions();
    bc.add_dirichlet(4, "z", "0");
    bc.add_dirichlet(6, "x,y,z", "0; 0; 0");
    bc.add_dirichlet(5, "z", fmt(-delta) + "*t");
    const auto start = std::chrono::steady_clock::now();
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "mechanics");
      solver.setup();
      solver.solve_quasi_static(1.0);
    }
    const double solve_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double F = -solver.reaction_force(5)[2]; // compressive load carried [N]
    if (!std::isfinite(F))
      throw NumericalFailure("reaction force", "upper platen (id 5)", "check the model");
    solver.write_output(ctx.output().path().string(), "solution", 0);

    // 4. Against E A / L.
    const fem::DensityModulusLaw law(p.density_modulus_law, p.constant_modulus, p.minimum_density,
                                     p.minimum_modulus);
    const double E = law.modulus(rho);
    const double A_mesh = model.mesh.total_volume() / L, A_exact = M_PI * ph.radius * ph.radius;
    const double K = F / delta, K_ref = E * A_mesh / L, K_exact = E * A_exact / L;
    double density_error = 0;
    for (const double d : model.mesh.cell_density)
      density_error = std::max(density_error, std::abs(d - rho) / rho);
    // Work of the platen force (linear: F delta / 2) equals the strain energy.
    const double energy_error =
        std::abs(solver.strain_energy() - 0.5 * F * delta) / (0.5 * std::abs(F) * delta);

    ctx.log() << std::setprecision(6) << "  E = " << E / 1e6 << " MPa, A_mesh = " << A_mesh * 1e6
              << " mm^2 (pi r^2 = " << A_exact * 1e6 << "), L = " << L * 1e3 << " mm\n  stiffness "
              << K / 1e3 << " N/mm, E A_mesh / L = " << K_ref / 1e3 << " N/mm, relative error "
              << std::abs(K - K_ref) / K_ref << "\n";
    ctx.history().add({{"displacement_mm", delta * 1e3}, {"reaction_force_N", F}});
    Summary& sum = ctx.summary();
    sum.set_figure("stiffness_relative_error", std::abs(K - K_ref) / K_ref, "-");
    sum.set_figure("stiffness_N_per_mm", K / 1e3, "N/mm");
    sum.set_figure("reference_stiffness_N_per_mm", K_ref / 1e3, "N/mm");
    sum.set_figure("stiffness_relative_error_exact_area", std::abs(K - K_exact) / K_exact, "-");
    sum.set_figure("area_relative_error", std::abs(A_mesh - A_exact) / A_exact, "-");
    sum.set_figure("density_relative_error", density_error, "-");
    sum.set_figure("energy_balance_error", energy_error, "-");
    sum.set_figure("reaction_force_N", F, "N");
    sum.set_figure("youngs_modulus_MPa", E / 1e6, "MPa");
    sum.set_figure("cells", tria.n_global_active_cells(), "-");
    sum.set_figure("mechanics_dofs", solver.dof_handler().n_dofs(), "-");
    sum.set_figure("solve_time", solve_time, "s");
  }

 private:
  PhantomParameters phantom_;
  ct::BoneParameters bone_;
  typename fem::MechanicsSolver<3>::Parameters mech_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(ct_phantom_cylinder, "ct_phantom_cylinder",
                           "synthetic CT cylinder of uniform density written, read back, "
                           "meshed and compressed: stiffness against E A / L.",
                           "mechanics", create_scenario<CtPhantomCylinder>,
                           {"Phantom", PhantomParameters::declare}, sections::bone(),
                           sections::mechanics())

} // namespace spinesim::applications
