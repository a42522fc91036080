// The coupling's checkpoint (FemParticleCoupling::save/load): a coupled state after a few
// explicit steps, saved and loaded into a fresh coupling on the same FEM state, gives back the
// same particles bit for bit (positions, volumes, displacements, velocities, free flags) and
// the same totals, in 2-D and 3-D (and on 2 ranks when run under mpiexec). With NOSB-PD
// or SPG particles of a J2 material past yield, the material history comes back too (the same
// equivalent plastic strains and stored energy). A run that diverges is stopped by the speed
// check of the coupled step.
#include "base/exceptions.h"
#include "coupled_setup.h" // this directory: the coupling tests' shared model
#include "coupling/fem_particle_coupling.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "meshfree/particle_method.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace spinesim::coupling {
namespace {

using testing_setup::CoupledSetup;

template <int dim>
void checkpoint_round_trip(const std::string& method, double second_youngs = 0) {
  const MPI_Comm comm = MPI_COMM_WORLD;
  CoupledSetup<dim> setup(method, method == "nosb" || method == "spg", second_youngs);
  auto& solver = *setup.solver;
  const auto& cp = setup.parameters;

  FemParticleCoupling<dim> a(cp, solver);
  a.initialise();
  ASSERT_GT(a.n_free_particles(), 0u);
  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    H[r][r] = 1e-4 * (r + 1);
  a.impose_affine(H);
  const double dt = a.stable_time_step();
  ASSERT_TRUE(std::isfinite(dt) && dt > 0);
  for (unsigned int n = 0; n < 5; ++n)
    a.step(dt);
  a.synchronise();
  const std::string file = std::string(SPINESIM_TEST_SCRATCH_DIR) + "/coupling_checkpoint_" +
                           std::to_string(dim) + "d.txt";
  a.save(file);
  MPI_Barrier(comm);

  FemParticleCoupling<dim> b(cp, solver);
  b.load(file);
  b.synchronise();
  EXPECT_EQ(b.n_free_particles(), a.n_free_particles());
  EXPECT_EQ(b.n_ghost_particles(), a.n_ghost_particles());
  EXPECT_EQ(b.n_converted_cells(), a.n_converted_cells());
  const auto& pa = a.particles();
  const auto& pb = b.particles();
  ASSERT_EQ(pb.size(), pa.size());
  if (second_youngs > 0) { // the file holds two laws, and particles of each
    std::set<unsigned int> ids;
    for (unsigned int i = 0; i < pa.size(); ++i)
      ids.insert(pa.material_id(i));
    EXPECT_EQ(ids.size(), 2u);
  }
  for (unsigned int i = 0; i < pa.size(); ++i) {
    ASSERT_EQ(pb.reference_position(i), pa.reference_position(i)) << i;
    ASSERT_EQ(pb.volume(i), pa.volume(i)) << i;
    ASSERT_EQ(b.is_free(i), a.is_free(i)) << i;
    ASSERT_EQ(pb.material_id(i), pa.material_id(i)) << i;
    if (a.is_free(i)) { // ghosts are driven by the FEM, restored separately
      ASSERT_EQ(pb.displacement(i), pa.displacement(i)) << i;
      ASSERT_EQ(pb.velocity(i), pa.velocity(i)) << i;
    }
  }
  // Totals from the restored state: the same sums over the same values.
  EXPECT_DOUBLE_EQ(b.total_mass(), a.total_mass());
  EXPECT_DOUBLE_EQ(b.kinetic_energy(), a.kinetic_energy());
  EXPECT_DOUBLE_EQ(b.strain_energy(), a.strain_energy());
  const auto ea = a.equivalent_plastic_strains(), eb = b.equivalent_plastic_strains();
  ASSERT_EQ(ea.size(), eb.size());
  double largest = 0;
  for (unsigned int i = 0; i < ea.size(); ++i) {
    ASSERT_EQ(eb[i], ea[i]) << i;
    largest = std::max(largest, ea[i]);
  }
  if (method == "nosb" || method == "spg") {
    EXPECT_GT(largest, 0.0); // the test has history to restore
  }
}

// Steps far above the stable one make central differences grow without bound: the coupled
// step stops the run once a particle outruns the material's P wave, before anything is NaN.
template <int dim>
void divergence_is_caught() {
  CoupledSetup<dim> setup("bond_based", false);
  auto& solver = *setup.solver;
  const auto& cp = setup.parameters;
  FemParticleCoupling<dim> c(cp, solver);
  c.initialise();
  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int k = 0; k < dim; ++k)
      H[r][k] = 1e-4 * (1 + r + 2 * k);
  c.impose_affine(H); // free boundaries: this state is not in equilibrium and starts moving
  const double dt = 5 * c.stable_time_step();
  try {
    for (unsigned int n = 0; n < 2000; ++n)
      c.step(dt);
    ADD_FAILURE() << "2000 steps of 5x the stable step did not diverge";
  } catch (const NumericalFailure& e) {
    EXPECT_NE(std::string(e.what()).find("exceeds the P-wave speed"), std::string::npos)
        << e.what();
  }
}

// The manifest catches damage; a checkpoint edited and re-hashed reaches the loader. Cut in
// half, with a particle count no file could hold (a loop or vector sized by it would run for
// hours or exhaust memory), or with a particle's free flag out of range: each is InvalidInput
// naming the file, before any particle of it is used.
template <int dim>
void damaged_checkpoint_is_invalid_input() {
  const MPI_Comm comm = MPI_COMM_WORLD;
  CoupledSetup<dim> setup("nosb", true);
  FemParticleCoupling<dim> a(setup.parameters, *setup.solver);
  a.initialise();
  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    H[r][r] = 1e-4 * (r + 1);
  a.impose_affine(H);
  a.step(a.stable_time_step());
  const std::string base =
      std::string(SPINESIM_TEST_SCRATCH_DIR) + "/damaged_checkpoint_" + std::to_string(dim) + "d";
  a.save(base + ".txt");
  MPI_Barrier(comm);
  std::ifstream in(base + ".txt");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    lines.push_back(line);
  ASSERT_GT(lines.size(), 3u);
  std::istringstream header(lines[1]);
  std::vector<std::string> counts;
  for (std::string token; header >> token;)
    counts.push_back(token);
  // time, particles, converted cells, broken, dissipation, heat, history, last force pass, laws,
  // contact stick points, short-range pairs born closer
  ASSERT_EQ(counts.size(), 11u);
  const std::size_t first_law = 2 + std::stoul(counts[2]);
  const std::size_t first_particle = first_law + std::stoul(counts[8]);
  ASSERT_GT(first_particle, first_law);
  ASSERT_LT(first_particle, lines.size());

  const auto joined = [](const std::vector<std::string>& l, std::size_t n) {
    std::string text;
    for (std::size_t k = 0; k < n; ++k)
      text += l[k] + "\n";
    return text;
  };
  std::vector<std::string> variants;
  const std::string whole = joined(lines, lines.size());
  variants.push_back(whole.substr(0, whole.size() / 2)); // cut in half
  auto edited = lines;
  const std::string setup_counts_particles = counts[1];
  counts[1] = "1000000000000";
  edited[1].clear();
  for (const auto& c : counts)
    edited[1] += c + " ";
  variants.push_back(joined(edited, edited.size()));
  // More contact stick points than the file could hold.
  counts[1] = setup_counts_particles;
  counts[9] = "1000000000000";
  edited = lines;
  edited[1].clear();
  for (const auto& c : counts)
    edited[1] += c + " ";
  variants.push_back(joined(edited, edited.size()));
  edited = lines;
  std::istringstream particle(lines[first_particle]);
  std::vector<std::string> fields;
  for (std::string token; particle >> token;)
    fields.push_back(token);
  fields[2] = "7"; // the free flag: 0 or 1
  edited[first_particle].clear();
  for (const auto& f : fields)
    edited[first_particle] += f + " ";
  variants.push_back(joined(edited, edited.size()));
  // The particle's law index past the laws the file holds.
  fields.clear();
  std::istringstream again(lines[first_particle]);
  for (std::string token; again >> token;)
    fields.push_back(token);
  fields.back() = counts[8];
  edited = lines;
  edited[first_particle].clear();
  for (const auto& f : fields)
    edited[first_particle] += f + " ";
  variants.push_back(joined(edited, edited.size()));
  // A law of a model the program does not have.
  edited = lines;
  edited[first_law] = "plasticine" + lines[first_law].substr(lines[first_law].find(' '));
  variants.push_back(joined(edited, edited.size()));

  for (std::size_t v = 0; v < variants.size(); ++v) {
    const std::string file = base + "_" + std::to_string(v) + ".txt";
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      std::ofstream(file) << variants[v];
    MPI_Barrier(comm);
    FemParticleCoupling<dim> b(setup.parameters, *setup.solver);
    try {
      b.load(file);
      ADD_FAILURE() << "variant " << v << " loaded";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.where(), file) << "variant " << v;
    }
  }
}

TEST(CouplingCheckpoint, DamagedFileIsInvalidInput2D) {
  damaged_checkpoint_is_invalid_input<2>();
}
TEST(CouplingCheckpoint, DamagedFileIsInvalidInput3D) {
  damaged_checkpoint_is_invalid_input<3>();
}
// Strain energy density [J/m^3] of an isotropic solid at displacement gradient H: small
// strain (the FEM cells) or St. Venant-Kirchhoff, the finite-strain form of linear_elastic that
// NOSB-PD and SPG particles evaluate at F = I + H. 2-D: plane strain.
template <int dim>
double energy_density(const dealii::Tensor<2, dim>& H, double E, double nu, bool finite) {
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  dealii::Tensor<2, dim> e = 0.5 * (H + transpose(H));
  if (finite)
    e += 0.5 * transpose(H) * H;
  return 0.5 * lambda * trace(e) * trace(e) + mu * scalar_product(e, e);
}

// Cells of two materials (E 17 GPa left of x = 0.5, 110 GPa right) convert into particles that
// each run their host cell's law. Under an affine displacement every family's (every smoothed)
// deformation gradient is exact, across the interface as well, so the particles' stored energy
// is each material's St. Venant-Kirchhoff energy density times its particles' volume.
// Round-off bounds the difference (1e-10); particles given one law for both materials miss it
// by 73 % either way (all the softer law or all the stiffer one). The run then steps stably.
template <int dim>
void each_particle_runs_its_cells_law(const std::string& method) {
  const double E0 = 17e9, E1 = 110e9, nu = 0.25;
  CoupledSetup<dim> setup(method, false, E1);
  FemParticleCoupling<dim> c(setup.parameters, *setup.solver);
  c.initialise();
  ASSERT_GT(c.n_free_particles(), 0u);
  // Material ids index the particles' laws in the order the records arrived: one id on each
  // side of x = 0.5, two different ones.
  const auto& p = c.particles();
  std::set<unsigned int> ids[2];
  for (unsigned int i = 0; i < p.size(); ++i)
    ids[p.reference_position(i)[0] > 0.5 ? 1 : 0].insert(p.material_id(i));
  ASSERT_EQ(ids[0].size(), 1u);
  ASSERT_EQ(ids[1].size(), 1u);
  EXPECT_NE(*ids[0].begin(), *ids[1].begin());

  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int k = 0; k < dim; ++k)
      H[r][k] = 1e-4 * (1 + r + k); // symmetric: strain without rotation
  c.impose_affine(H);
  c.synchronise();
  // The particles fill [0.25, 0.75]^dim of the unit square (cube), half of it in each
  // material. The FEM cells' share (small strain, per cell law) is the FEM's own account.
  const double particle_volume = std::pow(0.5, dim) / 2;
  double expected = 0;
  for (const double E : {E0, E1})
    expected += particle_volume * energy_density(H, E, nu, true);
  const double energy = c.strain_energy() - setup.solver->strain_energy();
  ASSERT_TRUE(std::isfinite(energy));
  EXPECT_NEAR(energy, expected, 1e-10 * expected) << method << " " << dim << "-D";

  const double dt = c.stable_time_step();
  ASSERT_TRUE(std::isfinite(dt) && dt > 0);
  for (unsigned int n = 0; n < 20; ++n)
    c.step(dt);
  c.synchronise();
  EXPECT_TRUE(std::isfinite(c.strain_energy()));
  EXPECT_TRUE(std::isfinite(c.kinetic_energy()));
}

TEST(CouplingMaterials, EachParticleRunsItsCellsLawNosb2D) {
  each_particle_runs_its_cells_law<2>("nosb");
}
TEST(CouplingMaterials, EachParticleRunsItsCellsLawNosb3D) {
  each_particle_runs_its_cells_law<3>("nosb");
}
TEST(CouplingMaterials, EachParticleRunsItsCellsLawSpg2D) {
  each_particle_runs_its_cells_law<2>("spg");
}
TEST(CouplingMaterials, EachParticleRunsItsCellsLawSpg3D) {
  each_particle_runs_its_cells_law<3>("spg");
}
// Bond-based PD calibrates each particle's micromodulus to its own law and joins two materials
// in series; its force kernel takes one critical stretch, so a fracture energy (a stretch per
// material) is refused naming the parameter, while one critical stretch for all runs.
template <int dim>
void bond_based_two_materials() {
  for (const bool from_fracture_energy : {false, true}) {
    CoupledSetup<dim> setup("bond_based", false, 110e9);
    dealii::ParameterHandler prm;
    meshfree::declare_particle_method_sections(prm);
    prm.enter_subsection("Bond based");
    prm.set("Plane model", "plane_strain");
    prm.set(from_fracture_energy ? "Fracture energy" : "Critical stretch", "100");
    prm.leave_subsection();
    setup.parameters.make_method = meshfree::particle_method_maker<dim>("bond_based", prm, "test");
    FemParticleCoupling<dim> c(setup.parameters, *setup.solver);
    if (from_fracture_energy) {
      try {
        c.initialise();
        ADD_FAILURE() << "one fracture energy for two materials accepted";
      } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("Bond based/Fracture energy"), std::string::npos)
            << e.what();
      }
      continue;
    }
    c.initialise();
    std::set<unsigned int> ids;
    for (unsigned int i = 0; i < c.particles().size(); ++i)
      ids.insert(c.particles().material_id(i));
    EXPECT_EQ(ids.size(), 2u);
    dealii::Tensor<2, dim> H;
    for (unsigned int r = 0; r < dim; ++r)
      H[r][r] = 1e-4;
    c.impose_affine(H);
    const double dt = c.stable_time_step();
    ASSERT_TRUE(std::isfinite(dt) && dt > 0);
    for (unsigned int n = 0; n < 20; ++n)
      c.step(dt);
    c.synchronise();
    EXPECT_TRUE(std::isfinite(c.strain_energy()) && c.strain_energy() > 0);
  }
}
TEST(CouplingMaterials, BondBasedTwoMaterials2D) {
  bond_based_two_materials<2>();
}
TEST(CouplingMaterials, BondBasedTwoMaterials3D) {
  bond_based_two_materials<3>();
}

// Two materials' laws and the particles' indices come back from a checkpoint.
TEST(CouplingCheckpoint, TwoMaterialsRoundTrip2D) {
  checkpoint_round_trip<2>("nosb", 110e9);
}
TEST(CouplingCheckpoint, TwoMaterialsRoundTrip3D) {
  checkpoint_round_trip<3>("spg", 110e9);
}

TEST(CoupledStep, DivergenceIsCaught2D) {
  divergence_is_caught<2>();
}
TEST(CoupledStep, DivergenceIsCaught3D) {
  divergence_is_caught<3>();
}
TEST(CouplingCheckpoint, SpgHistoryRoundTrip2D) {
  checkpoint_round_trip<2>("spg");
}
TEST(CouplingCheckpoint, SpgHistoryRoundTrip3D) {
  checkpoint_round_trip<3>("spg");
}
TEST(CouplingCheckpoint, RoundTrip2D) {
  checkpoint_round_trip<2>("bond_based");
}
TEST(CouplingCheckpoint, RoundTrip3D) {
  checkpoint_round_trip<3>("bond_based");
}
TEST(CouplingCheckpoint, NosbHistoryRoundTrip2D) {
  checkpoint_round_trip<2>("nosb");
}
TEST(CouplingCheckpoint, NosbHistoryRoundTrip3D) {
  checkpoint_round_trip<3>("nosb");
}

} // namespace
} // namespace spinesim::coupling
