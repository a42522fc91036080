// The `ct_to_particles` scenario (also `spinesim convert SCENE`): builds the CT model of a
// scene (sections CT, Bone, Caps, as vertebra_compression does) and turns it into a particle
// cloud, one particle per cell (at its centre) or per Gauss point of the 2x2x2 rule, each
// with its volume (JxW), density [g/cm^3] and material id, written to <run dir>/<name>.vtu and
// <name>.h5 (datasets positions, volumes, density, material_id; fem/ct/mesh_to_particles.h).
// It checks the conversion conserves what it must: particle count (cells or 8 cells), total
// volume (= mesh volume) and total mass (= the CT model's mass, sum of rho V over cells), and
// reports the relative differences as figures.

#include "applications/common_sections.h"
#include "applications/ct/ct_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/ct/ct_model.h"
#include "fem/ct/mesh_to_particles.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>

#include <algorithm>
#include <cmath>

namespace spinesim::applications {

using namespace framework;

namespace {

struct ConversionParameters {
  std::string placement = "cell";
  std::string name = "particles";
  unsigned int refinements = 0;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Per", "cell", Selection("cell|quadrature"),
                      "One particle per cell (at its centre) or per Gauss point of the 2x2x2 "
                      "rule, each with the volume it represents [-].");
    prm.declare_entry("File name", "particles", Anything(),
                      "Base name of the .vtu and .h5 files in the run directory [-].");
    prm.declare_entry("Global refinements", "0", Integer(0, 3),
                      "Uniform refinements of the voxel mesh before conversion [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    placement = prm.get("Per");
    name = prm.get("File name");
    refinements = prm.get_integer("Global refinements");
    if (name.empty() || name.find('/') != std::string::npos)
      throw InvalidInput("Particle conversion/File name", "'" + name + "'",
                         "a plain file name without directories");
  }
};

class CtToParticles : public Scenario {
 public:
  explicit CtToParticles(const ScenarioFactoryArgs& args) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3 (CT volumes are 3-D)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Bone", bone_);
    parse_section(prm, "Caps", caps_);
    parse_section(prm, "Particle conversion", conversion_);
    ct_ = ct::read_ct_parameters(prm, bone_, nullptr);
    ct_.mark_end_faces = false; // no loads here
    // Caps (when meshed) get their density, as in vertebra_compression; no end faces needed.
    bool caps_meshed = true;
    for (int l : caps_.labels)
      caps_meshed &= std::find(ct_.labels.begin(), ct_.labels.end(), l) != ct_.labels.end();
    if (caps_meshed)
      for (int l : caps_.labels) {
        ct_.label_moduli[l] = caps_.youngs_modulus;
        ct_.label_densities[l] = caps_.density / 1000.0;
      }
  }

  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<3> tria(ctx.comm());
    fem::CtModel model;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "ct model");
      model = fem::build_ct_model(ct_, tria);
    }
    ctx.log() << "  image: " << ct_.image_file << "\n  " << model.summary() << "\n";
    for (const auto& warning : model.warnings)
      ctx.warn(warning);
    if (conversion_.refinements > 0)
      tria.refine_global(conversion_.refinements);

    const bool per_cell = conversion_.placement == "cell";
    fem::ParticleCloud<3> cloud;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "conversion");
      cloud = fem::mesh_to_particles(tria, model.mesh.cell_density,
                                     per_cell ? fem::ParticlePlacement::cell_centre
                                              : fem::ParticlePlacement::gauss_points);
    }
    const std::string base = (ctx.output().path() / conversion_.name).string();
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "output");
      fem::write_particles_vtu(cloud, base + ".vtu", ctx.comm());
      fem::write_particles_hdf5(cloud, base + ".h5", ctx.comm());
    }

    // Conservation: particles against the mesh they came from.
    double volume = 0, mass = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      volume += cloud.volumes[i];
      mass += 1000.0 * cloud.density[i] * cloud.volumes[i]; // [kg]
    }
    const MPI_Comm comm = ctx.comm();
    volume = dealii::Utilities::MPI::sum(volume, comm);
    mass = dealii::Utilities::MPI::sum(mass, comm);
    const double n = dealii::Utilities::MPI::sum(double(cloud.size()), comm);
    const double expected = double(tria.n_global_active_cells()) * (per_cell ? 1 : 8);
    const double mesh_volume = model.mesh.total_volume(), mesh_mass = model.mesh.total_mass();
    if (!std::isfinite(mass) || !(mesh_volume > 0))
      throw NumericalFailure("particle sums", "conversion of " + ct_.image_file,
                             "check the CT calibration");

    ctx.log() << "  " << n << " particles (" << conversion_.placement << ") written to " << base
              << ".vtu / .h5; volume " << volume * 1e6 << " cm^3 (mesh " << mesh_volume * 1e6
              << "), mass " << mass * 1e3 << " g (mesh " << mesh_mass * 1e3 << ")\n";
    Summary& sum = ctx.summary();
    sum.set_figure("particles", n, "-");
    sum.set_figure("particle_count_mismatch", std::abs(n - expected), "-");
    sum.set_figure("particle_volume_cm3", volume * 1e6, "cm^3");
    sum.set_figure("mesh_volume_cm3", mesh_volume * 1e6, "cm^3");
    sum.set_figure("volume_relative_error", std::abs(volume - mesh_volume) / mesh_volume, "-");
    sum.set_figure("particle_mass_g", mass * 1e3, "g");
    sum.set_figure("mesh_mass_g", mesh_mass * 1e3, "g");
    sum.set_figure("mass_relative_error", std::abs(mass - mesh_mass) / std::abs(mesh_mass), "-");
    sum.set_figure("cells", tria.n_global_active_cells(), "-");
    ctx.summary().set_label("placement", conversion_.placement);
  }

 private:
  ct::BoneParameters bone_;
  ct::CapsParameters caps_;
  ConversionParameters conversion_;
  fem::CtParameters ct_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(ct_to_particles, "ct_to_particles",
                           "CT model of the scene's CT section converted to particles (per cell "
                           "or Gauss point) in VTU and HDF5; checks count, volume and mass.",
                           "mechanics", create_scenario<CtToParticles>, sections::ct(),
                           sections::bone(), sections::caps(),
                           {"Particle conversion", ConversionParameters::declare})

} // namespace spinesim::applications
