#include "applications/simulation/particle_zone.h"

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/simulation/zone_energy.h"
#include "applications/simulation/zone_partition.h"
#include "base/exceptions.h"
#include "base/expression_function.h"
#include "base/list_parsing.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/adaptive_dynamic_relaxation.h"
#include "meshfree/bond_based_method.h"
#include "meshfree/fragments.h"
#include "meshfree/implicit/implicit_static_solver.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_method.h"
#include "meshfree/particle_output.h"
#include "meshfree/particle_set.h"
#include "meshfree/pre_crack.h"
#include "meshfree/velocity_verlet.h"

#include <deal.II/base/function_parser.h>
#include <deal.II/base/utilities.h>
#include <deal.II/lac/vector.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {
std::vector<double> doubles(const std::string& list, const std::string& where, unsigned int n_min) {
  const auto values = parse_number_list(list, where);
  if (values.size() < n_min)
    throw InvalidInput(where, "needs at least " + std::to_string(n_min) + " numbers",
                       "comma-separated coordinates [m]");
  return values;
}
} // namespace

void ParticleZoneParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Lower corner", "-0.5, -0.5, -0.5", Anything(),
                    "Lower corner of the particle lattice box (dim values) [m].");
  prm.declare_entry("Upper corner", "0.5, 0.5, 0.5", Anything(),
                    "Upper corner of the particle lattice box (dim values) [m].");
  prm.declare_entry("Spacing", "0.05", Double(0), "Lattice spacing h [m].");
  prm.declare_entry("Shape", "box", Selection("box|annulus|spherical_shell"),
                    "Which lattice points of the box make the body [-]: box (all); annulus "
                    "(Inner radius <= r <= Outer radius, r the distance from Centre in the x-y "
                    "plane: a ring in 2-D, a tube along z in 3-D; with an Outer radius beyond "
                    "the box, a plate or block with a hole); spherical_shell (r the "
                    "distance in space). The lattice stays uniform (spacing h), which keeps "
                    "bond-based PD's calibration.");
  prm.declare_entry("Centre", "0, 0, 0", Anything(),
                    "Centre of the annulus or shell, and of the regions' Radial range (dim "
                    "values) [m].");
  prm.declare_entry("Inner radius", "0", Double(0), "Inner radius of the annulus or shell [m].");
  prm.declare_entry("Outer radius", "0", Double(0),
                    "Outer radius of the annulus or shell; must exceed the inner radius [m].");
  prm.declare_entry("Initial velocity", "", Anything(),
                    "Velocity at t = 0 of the free components, dim ';'-separated expressions "
                    "in x, y, z (reference position), e.g. the radial field v0 x/r; v0 y/r; "
                    "empty = at rest [m/s]. Its kinetic energy enters the energy account as "
                    "the initial energy (Simulation/Energy account).");
  prm.declare_entry("Integration", "explicit", Selection("explicit|quasi_static"),
                    "explicit: velocity Verlet sub-stepped at the stable step; quasi_static: "
                    "adaptive dynamic relaxation to equilibrium at every step [-].");
  prm.declare_entry("Time step safety", "0.8", Double(0, 1),
                    "Fraction of the stable time step used by explicit steps [-].");
  prm.declare_entry("Damping", "0", Double(0),
                    "Mass-proportional damping of explicit steps (velocity decay rate) [1/s].");
  prm.declare_entry("Reaction region", "-1", Integer(-1, n_region_slots),
                    "Loaded region whose reaction force is reported; -1 = none [-].");
  // One subsection per registered particle method ("Bond based", "NOSB", ...).
  meshfree::declare_particle_method_sections(prm);
  prm.enter_subsection("Quasi-static");
  meshfree::AdaptiveDynamicRelaxationParameters::declare(prm);
  prm.declare_entry("Step cuts", "6", Integer(0, 30),
                    "How often a load step whose relaxation does not converge within Maximum "
                    "iterations is cut: the state at its start is restored (broken bonds and "
                    "material history included) and the load applied in two halves, each cut "
                    "again if needed; after two converged sub-steps the sub-step doubles again "
                    "[-]. 0 = the run stops at the first relaxation that does not converge.");
  prm.declare_entry("Solver", "relaxation", Selection("relaxation|newton"),
                    "How each load step reaches equilibrium [-]. relaxation: adaptive dynamic "
                    "relaxation (Kilic & Madenci 2010), every particle method. newton: Newton's "
                    "method with the analytic tangent of bond-based PD (Jo & Ha 2021, eq. 20) "
                    "and a Trilinos linear solver, on the zone's ranks; bonds break at "
                    "converged states and the step is solved again until none breaks. Both "
                    "stop at Tolerance.");
  prm.declare_entry("Break bonds", "while relaxing", Selection("while relaxing|at equilibrium"),
                    "When Solver = relaxation breaks bonds (Effects/Damage) [-]. while "
                    "relaxing: in every force pass of the relaxation, its transient included. "
                    "at equilibrium: none while relaxing; at the converged state one pass "
                    "breaks what is over its limit, and the step is relaxed again until none "
                    "breaks (at most Breaking passes), as Newton does.");
  prm.declare_entry("Newton iterations", "25", Integer(1),
                    "Newton iterations of one solve before the step counts as not converged "
                    "(and is cut, Step cuts) [-].");
  prm.declare_entry("Breaking passes", "100", Integer(1),
                    "Solves of one load step while bonds keep breaking, by Newton or by a "
                    "relaxation that breaks bonds at equilibrium [-].");
  prm.declare_entry("Linear solver", "amg", Selection("amg|jacobi|cg"),
                    "Linear solver of the Newton systems [-]: amg (CG + ML smoothed aggregation "
                    "with rigid-body modes), jacobi (diagonal PCG), cg.");
  prm.declare_entry("Linear tolerance", "1e-6", Double(0, 1),
                    "Relative residual at which a Newton system's solve stops [-].");
  prm.declare_entry("AMG rebuild ratio", "2", Double(0),
                    "amg: the later Newton systems of a load step keep the AMG hierarchy "
                    "built for an earlier one while their CG takes at most this multiple of "
                    "the iterations of its first solve (a lagged preconditioner: each solve "
                    "still reaches Linear tolerance); 0 = a new hierarchy every Newton "
                    "iteration [-].");
  // One sweep: on the cracked plate's Newton systems (12.5 and 6.25 mm) one Chebyshev sweep
  // per level took 27 % less time than two, with the same Newton iterations and bonds broken;
  // the extra CG iterations cost less than the second sweep on the fine level.
  prm.declare_entry("AMG smoother sweeps", "1", Integer(1),
                    "amg: Chebyshev smoother sweeps per level of the ML hierarchy [-]. More "
                    "sweeps take fewer CG iterations, each dearer.");
  prm.leave_subsection();
  for (unsigned int k = 1; k <= n_region_slots; ++k) {
    prm.enter_subsection("Region " + std::to_string(k));
    prm.declare_entry("Lower corner", "", Anything(),
                      "Lower corner of the box whose particles are prescribed; empty = slot "
                      "unused [m].");
    prm.declare_entry("Upper corner", "", Anything(), "Upper corner of the box [m].");
    prm.declare_entry("Radial range", "", Anything(),
                      "Optional 'r1, r2': only the box's particles at a distance r1 <= r <= r2 "
                      "from Particles/Centre, r in the x-y plane (a ring, in 3-D a tube along "
                      "z), e.g. a volume-constraint layer round a hole; empty = the whole box "
                      "[m].");
    prm.declare_entry("Components", "x,y", Anything(),
                      "Prescribed components, letters from x,y,z [-].");
    prm.declare_entry("Values", "0; 0", Anything(),
                      "Displacement per listed component, ';'-separated expressions in x, y, "
                      "z (reference position) and t [m].");
    prm.leave_subsection();
  }
  for (unsigned int k = 1; k <= n_crack_slots; ++k) {
    prm.enter_subsection("Crack " + std::to_string(k));
    prm.declare_entry("Corners", "", Anything(),
                      "Pre-crack: 2-D segment 'x1,y1; x2,y2', 3-D planar quadrilateral "
                      "'x1,y1,z1; ...; x4,y4,z4'; empty = slot unused [m].");
    prm.leave_subsection();
  }
}

void ParticleZoneParameters::parse(dealii::ParameterHandler& prm) {
  lower = doubles(prm.get("Lower corner"), "Particles/Lower corner", 2);
  upper = doubles(prm.get("Upper corner"), "Particles/Upper corner", 2);
  spacing = prm.get_double("Spacing");
  if (!(spacing > 0))
    throw InvalidInput("Particles/Spacing", "must be positive", "a lattice spacing h > 0 [m]");
  for (unsigned int d = 0; d < std::min(lower.size(), upper.size()); ++d)
    if (!(upper[d] > lower[d]))
      throw InvalidInput("Particles/Upper corner",
                         "not above Particles/Lower corner in direction " + std::to_string(d),
                         "an upper corner above the lower one in every direction [m]");
  shape = prm.get("Shape");
  inner_radius = prm.get_double("Inner radius");
  outer_radius = prm.get_double("Outer radius");
  centre = doubles(prm.get("Centre"), "Particles/Centre", 2); // also the Radial ranges'
  if (shape != "box") {
    if (!(outer_radius > inner_radius))
      throw InvalidInput("Particles/Outer radius",
                         std::to_string(outer_radius) + " is not above the Inner radius " +
                             std::to_string(inner_radius),
                         "an outer radius above the inner radius for Shape = " + shape + " [m]");
  }
  initial_velocity = prm.get("Initial velocity");
  integration = prm.get("Integration");
  time_step_safety = prm.get_double("Time step safety");
  damping = prm.get_double("Damping");
  reaction_region = prm.get_integer("Reaction region");
  regions.clear();
  for (unsigned int k = 1; k <= n_region_slots; ++k) {
    prm.enter_subsection("Region " + std::to_string(k));
    const std::string where = "Particles/Region " + std::to_string(k);
    if (!prm.get("Lower corner").empty()) {
      Region r;
      r.lower = doubles(prm.get("Lower corner"), where + "/Lower corner", 2);
      r.upper = doubles(prm.get("Upper corner"), where + "/Upper corner", 2);
      if (!prm.get("Radial range").empty()) {
        r.radial_range = doubles(prm.get("Radial range"), where + "/Radial range", 2);
        if (r.radial_range.size() != 2 || !(r.radial_range[0] >= 0) ||
            !(r.radial_range[1] > r.radial_range[0]))
          throw InvalidInput(where + "/Radial range",
                             "'" + prm.get("Radial range") + "' is not a range of radii",
                             "two radii 0 <= r1 < r2 [m]");
      }
      r.components = prm.get("Components");
      r.values = prm.get("Values");
      regions.push_back(r);
    } else if (reaction_region == int(k)) {
      prm.leave_subsection();
      throw InvalidInput("Particles/Reaction region", "names an unused region slot",
                         "a slot with a Lower corner");
    }
    prm.leave_subsection();
  }
  cracks.clear();
  for (unsigned int k = 1; k <= n_crack_slots; ++k) {
    prm.enter_subsection("Crack " + std::to_string(k));
    const std::string corners = prm.get("Corners");
    prm.leave_subsection();
    if (corners.empty())
      continue;
    cracks.push_back(corners); // read per dimension in setup()
  }
}

template <int dim>
struct ParticleZone<dim>::Impl {
  struct PrescribedRegion {
    std::vector<unsigned int> particles;
    std::vector<unsigned int> components;
    std::unique_ptr<dealii::FunctionParser<dim>> values; // one component per listed letter
  };

  ParticleZoneParameters prm;
  materials::LawParameters law;
  meshfree::AdaptiveDynamicRelaxationParameters adr_prm;
  // Particles/Quasi-static/Solver = newton: the implicit solver on the bond-based model.
  bool newton_steps = false;
  // Solver = relaxation with Break bonds = at equilibrium (relax_at_equilibrium()), and the
  // pseudo-steps of the step's passes before the current one (a failed attempt counts them).
  bool break_at_equilibrium = false;
  unsigned int earlier_pass_iterations = 0;
  meshfree::ImplicitStaticSolverParameters newton_prm;
  std::unique_ptr<meshfree::ImplicitStaticSolver<dim>> newton;
  bool damage = false;

  meshfree::ParticleSet<dim> particles;
  meshfree::BondList<dim> bonds;
  std::unique_ptr<meshfree::ParticleMethod<dim>> method;
  std::unique_ptr<meshfree::VelocityVerlet<dim>> verlet;
  std::vector<PrescribedRegion> regions;
  std::vector<double> stiffness_bound;
  double time = 0, dt_stable = 0;
  bool account = false;
  ZoneEnergy<dim> energy;
  std::vector<dealii::Tensor<1, dim>> forces_before; // of the last force pass, before breaks
  double max_speed = 0;                              // over the run [m/s]
  std::size_t broke_since_step_check = 0; // bond ends broken since the stable step was taken
  // Off for the pass a restart makes at the checkpoint's displacements: its breaks were taken
  // there already, and the rows they rebuilt must not break again before the next step.
  bool passes_break = true;
  bool account_restored = true; // false: a restart from a checkpoint without the account
  unsigned int explicit_steps = 0, relaxation_iterations = 0;
  // Quasi-static step cuts (Particles/Quasi-static/Step cuts): the most a step is halved, the
  // load sub-step the next step starts with [s] (0: the whole step), the converged sub-steps
  // since the last cut or growth, the cuts of the run, and the log lines they made.
  unsigned int max_step_cuts = 6;
  double sub_step = 0;
  unsigned int sub_steps_converged = 0, step_cuts = 0;
  std::vector<std::string> messages;
  double advance_seconds = 0;       // wall time in advance_to [s]
  std::size_t broken_initially = 0; // bond ends cut by pre-cracks, over all ranks
  std::uint64_t n_bonds_global = 0; // pairs, over all ranks
  std::uint64_t n_global = 0;       // particles, over all ranks

  // Distributed zone (zone_partition.h): owned particles first, ghosts after.
  MPI_Comm comm = MPI_COMM_SELF;
  std::unique_ptr<ZonePartition<dim>> partition;
  unsigned int n_owned() const { return partition ? partition->n_owned() : particles.size(); }
  double sum(double x) const { return partition ? dealii::Utilities::MPI::sum(x, comm) : x; }
  double max(double x) const { return partition ? dealii::Utilities::MPI::max(x, comm) : x; }
  double min(double x) const { return partition ? dealii::Utilities::MPI::min(x, comm) : x; }

  // Runs f on every rank of a distributed zone and, if it threw on any rank, throws the first
  // such rank's report on all of them (NumericalFailure and InvalidInput as such, anything
  // else as std::runtime_error): the others would otherwise wait in the next collective call.
  // f must make no collective call itself. One reduction. Not distributed: f alone.
  template <class F>
  void collectively(F&& f) const {
    if (!partition)
      return f();
    int kind = 0; // 1 numerical failure, 2 bad input
    std::string a, b, c;
    try {
      f();
    } catch (const NumericalFailure& e) {
      kind = 1;
      a = e.what_failed();
      b = e.location();
      c = e.hint();
    } catch (const InvalidInput& e) {
      kind = 2;
      a = e.where();
      b = e.problem();
      c = e.allowed();
    } catch (const std::exception& e) { // e.g. a checkpoint file that cannot be written
      kind = 3;
      a = e.what();
    }
    const unsigned int ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
    const unsigned int first = dealii::Utilities::MPI::min(
        kind == 0 ? ranks : dealii::Utilities::MPI::this_mpi_process(comm), comm);
    if (first == ranks)
      return;
    kind = dealii::Utilities::MPI::broadcast(comm, kind, first);
    a = dealii::Utilities::MPI::broadcast(comm, a, first);
    b = dealii::Utilities::MPI::broadcast(comm, b, first);
    c = dealii::Utilities::MPI::broadcast(comm, c, first);
    const std::string rank = " (MPI rank " + std::to_string(first) + ")";
    if (kind == 1) {
      NumericalFailure failure(a, b + rank, c);
      failure.set_collective();
      throw failure;
    }
    if (kind == 2)
      throw InvalidInput(a, b + rank, c);
    throw std::runtime_error(a + rank);
  }

  void compute_forces(meshfree::ParticleSet<dim>& p) {
    if (partition)
      partition->update_ghosts(p.displacements()); // the ghosts' positions of this pass
    if (!shares_breaks()) {
      collectively([&] { // one reduction a force pass
        double before = 0;
        const std::size_t broke = force_pass(p, before);
        book_breaks(p, before, broke);
      });
      return;
    }
    // A distributed SPG zone (meshfree::ParticleMethod::set_break_decider): the pass decided
    // this rank's pairs (as lattice ids); every rank breaks everyone's now, before the next
    // pass. Only MPI calls run between the two reductions.
    double before = 0;
    std::vector<std::uint64_t> decided;
    collectively([&] {
      force_pass(p, before);
      const auto& ids = partition->ids();
      for (const auto& [i, j] : method->take_broken_pairs()) {
        decided.push_back(ids[i]);
        decided.push_back(ids[j]);
      }
    });
    std::size_t n_decided = 0; // over all ranks
    const std::vector<std::pair<unsigned int, unsigned int>> pairs =
        gather_broken_pairs(decided, n_decided);
    if (n_decided == 0)
      return book_breaks(p, before, 0); // throws nothing
    collectively([&] {
      method->break_pairs(p, bonds, pairs);
      book_breaks(p, before, 2 * n_decided);
    });
  }

  // The account's U of this rank: the owned particles' stored energy plus the plastic work
  // their history holds (ParticleMethod::plastic_work_density), the internal work as the FEM
  // counts it.
  double internal_energy(const meshfree::ParticleSet<dim>& p) const {
    return method->strain_energy(p, bonds) + plastic_work(p);
  }
  // The plastic work the owned particles' history holds [J] (2-D: J/m); 0 for a method or law
  // whose stored energy is not taken from the state.
  double plastic_work(const meshfree::ParticleSet<dim>& p) const {
    double e = 0;
    const auto d = method->plastic_work_density(p);
    for (unsigned int i = 0; i < d.size() && i < n_owned(); ++i)
      e += d[i] * p.volume(i);
    return e;
  }

  // Forces at the current displacements; returns the bond ends broken. With an account,
  // `before` is the stored energy before the pass's breaks.
  std::size_t force_pass(meshfree::ParticleSet<dim>& p, double& before) {
    const bool breaking = damage && passes_break;
    if (!account)
      return method->compute_forces(p, bonds, breaking);
    // The breaks of this pass release the stored energy they take away at these displacements
    // and the forces they remove (zone_energy.h): a pass without breaking gives the forces
    // before them (the price: two force passes a step with Damage on).
    before = internal_energy(p);
    if (breaking) {
      method->compute_forces_before_breaks(p, bonds);
      forces_before = p.forces();
    }
    return method->compute_forces(p, bonds, breaking);
  }

  void book_breaks(const meshfree::ParticleSet<dim>& p, double before, std::size_t broke) {
    broke_since_step_check += broke;
    if (!account)
      return;
    if (broke > 0)
      energy.force_pass(p, before, internal_energy(p), &forces_before);
    else
      energy.force_pass(p, before, before, nullptr);
  }

  // One load step by Newton (Particles/Quasi-static/Solver = newton), the load prescribed: Newton
  // to equilibrium without breaking, then one force pass of the zone that breaks what the
  // converged state breaks (and books it); while any broke, Newton again at the same load.
  // Its failures (a linear solve that does not converge, a non-finite residual or tangent)
  // are met on every rank alike: the norms and the solves are global.
  typename meshfree::AdaptiveDynamicRelaxation<dim>::Result newton_solve() {
    typename meshfree::AdaptiveDynamicRelaxation<dim>::Result result;
    if (partition) // the ghosts' prescribed values of this load
      partition->update_ghosts(particles.displacements());
    // A kept AMG hierarchy serves the Newton solves of one load step only: a run restarted
    // from a step's checkpoint then solves with the same preconditioners.
    newton->linear_solver().rebuild_next();
    try {
      for (unsigned int pass = 0; pass < newton_prm.max_breaking_passes; ++pass) {
        const auto nr = newton->newton(particles, bonds);
        result.iterations += nr.iterations;
        result.relative_residual = nr.relative_residual;
        if (!nr.converged)
          return result;
        const std::size_t before = broke_since_step_check;
        compute_forces(particles); // the zone's pass: breaks and their books
        if (sum(double(broke_since_step_check - before)) == 0) {
          result.converged = true;
          return result;
        }
      }
    } catch (NumericalFailure& e) {
      e.set_collective();
      throw;
    }
    return result; // bonds still breaking after Breaking passes
  }

  // One load step by dynamic relaxation with bonds breaking only at equilibrium (Break bonds =
  // at equilibrium): relax without breaking, then one force pass of the zone that breaks what
  // the converged state breaks (and books it); while any broke, relax again at the same load.
  typename meshfree::AdaptiveDynamicRelaxation<dim>::Result
  relax_at_equilibrium(meshfree::AdaptiveDynamicRelaxation<dim>& adr) {
    typename meshfree::AdaptiveDynamicRelaxation<dim>::Result result;
    struct Breaking { // breaking back on however the relaxation ends
      bool& flag;
      ~Breaking() { flag = true; }
    } restore{passes_break};
    earlier_pass_iterations = 0;
    for (unsigned int pass = 0; pass < newton_prm.max_breaking_passes; ++pass) {
      passes_break = false;
      const auto r = adr.solve(particles, stiffness_bound);
      passes_break = true;
      result.iterations += r.iterations;
      earlier_pass_iterations = result.iterations;
      result.relative_residual = r.relative_residual;
      if (!r.converged)
        return result;
      const std::size_t before = broke_since_step_check;
      compute_forces(particles); // the zone's pass: breaks and their books
      if (sum(double(broke_since_step_check - before)) == 0) {
        result.converged = true;
        return result;
      }
    }
    return result; // bonds still breaking after Breaking passes
  }

  // Whether copies of rows on several ranks share their breaks (SPG with a failure criterion
  // on more than one rank).
  bool shares_breaks() const {
    return partition && damage && method->shares_bond_breaks() &&
           !method->user_failure_criteria().empty();
  }

  // This rank's local index of lattice point `id`, or ~0u if it holds no such point (owned
  // and ghost ids are each ascending, zone_partition.h).
  unsigned int local_index(std::uint64_t id) const {
    const auto& ids = partition->ids();
    const auto owned_end = ids.begin() + partition->n_owned();
    for (const auto& [first, last] :
         {std::pair(ids.begin(), owned_end), std::pair(owned_end, ids.end())}) {
      const auto it = std::lower_bound(first, last, id);
      if (it != last && *it == id)
        return static_cast<unsigned int>(it - ids.begin());
    }
    return ~0u;
  }

  // Every rank's decided pairs of the last pass (`mine`: this rank's, lattice ids in pairs;
  // `n_decided` of them over all ranks), in this rank's indices, without the pairs it does not
  // hold both ends of. Collective (MPI_Allgather, and MPI_Allgatherv when any pair broke).
  std::vector<std::pair<unsigned int, unsigned int>>
  gather_broken_pairs(const std::vector<std::uint64_t>& mine, std::size_t& n_decided) const {
    const int ranks = static_cast<int>(dealii::Utilities::MPI::n_mpi_processes(comm));
    const int count = static_cast<int>(mine.size());
    std::vector<int> counts(ranks), offsets(ranks + 1, 0);
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
    for (int r = 0; r < ranks; ++r)
      offsets[r + 1] = offsets[r] + counts[r];
    n_decided = offsets[ranks] / 2;
    if (n_decided == 0)
      return {};
    std::vector<std::uint64_t> all(offsets[ranks]);
    MPI_Allgatherv(mine.data(), count, MPI_UINT64_T, all.data(), counts.data(), offsets.data(),
                   MPI_UINT64_T, comm);
    std::vector<std::pair<unsigned int, unsigned int>> pairs;
    for (std::size_t k = 0; k + 1 < all.size(); k += 2) {
      const unsigned int i = local_index(all[k]), j = local_index(all[k + 1]);
      if (i != ~0u && j != ~0u) // a row holds the bond only where both ends are
        pairs.emplace_back(i, j);
    }
    return pairs;
  }

  // Whether lattice point x lies in the body's shape (the Centre was checked in setup()).
  bool in_shape(const dealii::Point<dim>& x) const {
    if (prm.shape == "box")
      return true;
    const unsigned int radial_dims = prm.shape == "annulus" ? 2 : dim;
    double r2 = 0;
    for (unsigned int d = 0; d < radial_dims; ++d)
      r2 += (x[d] - prm.centre[d]) * (x[d] - prm.centre[d]);
    const double r = std::sqrt(r2);
    return r >= prm.inner_radius && r <= prm.outer_radius;
  }

  // This rank's part of the body (owned, then ghosts within ghost_reach), ghosts fixed.
  meshfree::ParticleSet<dim> distributed_body(double ghost_reach) {
    dealii::Point<dim> lo, hi;
    for (unsigned int d = 0; d < dim; ++d) {
      lo[d] = prm.lower[d];
      hi[d] = prm.upper[d];
    }
    partition = std::make_unique<ZonePartition<dim>>(
        comm, lo, hi, prm.spacing, ghost_reach,
        [this](const dealii::Point<dim>& x) { return in_shape(x); });
    if (dealii::Utilities::MPI::sum(partition->n_owned(), comm) == 0)
      throw InvalidInput("Particles/Shape", prm.shape + " holds no lattice point of the box",
                         "radii and a centre that put the shape inside the box");
    return local_set();
  }

  // The particles of the partition's points, ghosts fixed.
  meshfree::ParticleSet<dim> local_set() const {
    const double volume = partition->lattice_cell_volume() * (dim == 2 ? method->thickness() : 1);
    auto set = meshfree::ParticleSet<dim>::from_points(
        partition->points(), std::vector<double>(partition->points().size(), volume),
        method->thickness());
    for (unsigned int i = partition->n_owned(); i < set.size(); ++i)
      set.set_fixed(i); // moved by the exchange, never by the integrator
    set.set_density(law.density);
    return set;
  }

  // After the bonds are built (and, for a method whose forces need no neighbour rows, the
  // ghosts' rows dropped): only the ghosts some kept row bonds to stay. Bond-based: the first
  // layer (the second served its surface correction). NOSB-PD: both layers, the second
  // completing the first-layer ghosts' families, which the owned particles' forces gather.
  void drop_unbonded_ghosts() {
    const unsigned int n_owned = partition->n_owned(), n = particles.size();
    std::vector<std::uint8_t> keep(n - n_owned, 0);
    for (const unsigned int j : bonds.neighbor)
      if (j >= n_owned)
        keep[j - n_owned] = 1;
    for (unsigned int g = n_owned; g < n; ++g) // a ghost with a row stays, so rows compact
      if (bonds.end(g) > bonds.begin(g))
        keep[g - n_owned] = 1;
    const std::vector<unsigned int> index = partition->keep_ghosts(keep);
    for (unsigned int& j : bonds.neighbor)
      j = index[j];
    std::vector<std::size_t> offsets(partition->points().size() + 1, 0);
    for (unsigned int i = 0; i < n; ++i) // dropped ghosts have empty rows
      if (index[i] != ~0u)
        offsets[index[i] + 1] = bonds.offsets[i + 1];
    bonds.offsets = std::move(offsets);
    particles = local_set();
  }

  // Bond ends in the owned particles' rows (the ghosts' rows are their owners' to count).
  std::size_t owned_bond_ends() const { return bonds.offsets[n_owned()]; }
  std::size_t owned_broken_ends() const {
    std::size_t broken = 0;
    for (std::size_t k = 0; k < owned_bond_ends(); ++k)
      broken += bonds.broken[k] ? 1 : 0;
    return broken;
  }

  // The lattice points of the box inside the shape (the whole zone, on this rank).
  meshfree::ParticleSet<dim> body() const {
    dealii::Point<dim> lo, hi;
    for (unsigned int d = 0; d < dim; ++d) {
      lo[d] = prm.lower[d];
      hi[d] = prm.upper[d];
    }
    auto lattice = meshfree::ParticleSet<dim>::lattice(lo, hi, prm.spacing, method->thickness());
    if (prm.shape == "box")
      return lattice;
    std::vector<dealii::Point<dim>> points;
    std::vector<double> volumes;
    for (unsigned int i = 0; i < lattice.size(); ++i)
      if (in_shape(lattice.reference_position(i))) {
        points.push_back(lattice.reference_position(i));
        volumes.push_back(lattice.volume(i));
      }
    if (points.empty())
      throw InvalidInput("Particles/Shape", prm.shape + " holds no lattice point of the box",
                         "radii and a centre that put the shape inside the box");
    return meshfree::ParticleSet<dim>::from_points(points, volumes, method->thickness());
  }

  void set_initial_velocity() {
    if (prm.initial_velocity.empty())
      return;
    const auto v = parse_expressions<dim>(prm.initial_velocity, "Particles/Initial velocity", dim,
                                          false, "[m/s]");
    dealii::Vector<double> value(dim);
    for (unsigned int i = 0; i < n_owned(); ++i) { // ghosts stay at rest: the exchange moves them
      v->vector_value(particles.reference_position(i), value);
      for (unsigned int d = 0; d < dim; ++d) {
        if (!std::isfinite(value[d]))
          throw InvalidInput("Particles/Initial velocity",
                             "not finite at a particle (e.g. x/r at r = 0)",
                             "expressions finite at every particle of the body [m/s]");
        if (!particles.is_fixed(i, d))
          particles.velocities()[i][d] = value[d];
      }
    }
  }

  // What a quasi-static step changes, held in memory to go back to when its relaxation does
  // not converge: the particles' kinematics and damage, the broken bonds, the method's
  // committed material history (its checkpoint bytes), the clock and the step bounds.
  struct Snapshot {
    std::vector<dealii::Tensor<1, dim>> u, v, a, f;
    std::vector<double> damage, bound;
    std::vector<std::uint8_t> broken;
    std::string history;
    double time = 0, dt_stable = 0;
    std::size_t broke_since_step_check = 0;
  };
  Snapshot snapshot() const {
    Snapshot s{particles.displacements(),
               particles.velocities(),
               particles.accelerations(),
               particles.forces(),
               particles.damages(),
               stiffness_bound,
               bonds.broken,
               {},
               time,
               dt_stable,
               broke_since_step_check};
    std::ostringstream out;
    method->save(out);
    s.history = out.str();
    return s;
  }
  void restore(const Snapshot& s) {
    particles.displacements() = s.u;
    particles.velocities() = s.v;
    particles.accelerations() = s.a;
    particles.forces() = s.f;
    particles.damages() = s.damage;
    stiffness_bound = s.bound;
    // Bonds broken in the failed attempt heal: the families are rebuilt from the intact bonds
    // as a restart does (collective on a distributed zone: every rank rebuilds if any must).
    const bool changed = bonds.broken != s.broken;
    bonds.broken = s.broken;
    if (partition ? dealii::Utilities::MPI::logical_or(changed, comm) : changed)
      method->initialise(particles, bonds);
    std::istringstream in(s.history);
    method->load(in);
    time = s.time;
    dt_stable = s.dt_stable;
    broke_since_step_check = s.broke_since_step_check;
  }

  void prescribe(double t) {
    for (auto& r : regions) {
      dealii::Vector<double> value(r.components.size());
      for (const unsigned int i : r.particles) {
        const dealii::Point<dim>& x = particles.reference_position(i);
        r.values->set_time(t);
        r.values->vector_value(x, value);
        for (unsigned int c = 0; c < r.components.size(); ++c) {
          particles.displacements()[i][r.components[c]] = value[c];
          particles.velocities()[i][r.components[c]] = 0;
        }
      }
    }
  }

  meshfree::FragmentCount fragments() const {
    return partition ? distributed_fragments(bonds, *partition) : meshfree::count_fragments(bonds);
  }

  dealii::Tensor<1, dim> reaction() const {
    dealii::Tensor<1, dim> r;
    if (prm.reaction_region < 1)
      return r;
    // The supports balance the internal force on the prescribed particles.
    for (const unsigned int i : regions[prm.reaction_region - 1].particles)
      r -= particles.force(i);
    if (partition) // regions list owned particles
      for (unsigned int d = 0; d < dim; ++d)
        r[d] = dealii::Utilities::MPI::sum(r[d], comm);
    return r;
  }
};

template <int dim>
ParticleZone<dim>::ParticleZone(dealii::ParameterHandler& prm, const std::string& method,
                                bool damage)
    : impl_(std::make_unique<Impl>()) {
  parse_section(prm, "Material", impl_->law);
  parse_section(prm, "Particles", impl_->prm);
  parse_section(prm, std::vector<std::string>{"Particles", "Quasi-static"}, impl_->adr_prm);
  prm.enter_subsection("Particles");
  prm.enter_subsection("Quasi-static");
  impl_->max_step_cuts = prm.get_integer("Step cuts");
  impl_->newton_steps = prm.get("Solver") == "newton";
  impl_->break_at_equilibrium = prm.get("Break bonds") == "at equilibrium";
  {
    meshfree::ImplicitStaticSolverParameters& n = impl_->newton_prm;
    n.max_newton_iterations = prm.get_integer("Newton iterations");
    n.max_breaking_passes = prm.get_integer("Breaking passes");
    n.residual_tolerance = impl_->adr_prm.tolerance; // the free residual over the reactions
    n.displacement_tolerance = 0;
    n.linear.solver = prm.get("Linear solver");
    n.linear.tolerance = prm.get_double("Linear tolerance");
    n.linear.amg_rebuild_ratio = prm.get_double("AMG rebuild ratio");
    n.linear.amg_smoother_sweeps = prm.get_integer("AMG smoother sweeps");
  }
  prm.leave_subsection();
  prm.leave_subsection();
  impl_->damage = damage;
  const std::shared_ptr<const materials::ConstitutiveLaw> law = materials::create_law(impl_->law);
  const meshfree::ParticleMaterial material{
      impl_->law.youngs_modulus, impl_->law.poisson_ratio, impl_->law.density, law, 0.0, nullptr};
  prm.enter_subsection("Particles");
  meshfree::ParticleMethodMaker<dim> make;
  try {
    // SPG in a zone works on the zone's rows (its pre-cracks, breaks, ghosts and checkpoint):
    // only the total Lagrangian kernel uses them, the others search their own.
    if (method == "spg") {
      prm.enter_subsection("SPG");
      const std::string update = prm.get("Kernel update");
      prm.leave_subsection();
      if (update != "total_lagrangian")
        throw InvalidInput("Particles/SPG/Kernel update", "'" + update + "' in a particle zone",
                           "total_lagrangian (the zone's bonds, pre-cracks and breaks are its "
                           "rows)");
    }
    make = meshfree::particle_method_maker<dim>(method, prm, "Effects/Particles method");
  } catch (...) {
    prm.leave_subsection();
    throw;
  }
  prm.leave_subsection();
  impl_->method = make(material);
  if (impl_->newton_steps && impl_->prm.integration == "quasi_static" &&
      !dynamic_cast<const meshfree::BondBasedMethod<dim>*>(impl_->method.get()))
    throw InvalidInput("Particles/Quasi-static/Solver",
                       "newton with Effects/Particles method = " + method,
                       "relaxation, or newton with bond_based (the analytic tangent is "
                       "bond-based PD's)");
  if (impl_->prm.lower.size() < dim || impl_->prm.upper.size() < dim)
    throw InvalidInput("Particles/Lower corner", "needs one coordinate per dimension",
                       std::to_string(dim) + " comma-separated values [m]");
}

template <int dim>
ParticleZone<dim>::~ParticleZone() = default;

template <int dim>
void ParticleZone<dim>::setup(RunContext& ctx) {
  Impl& z = *impl_;
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d) {
    lo[d] = z.prm.lower[d];
    hi[d] = z.prm.upper[d];
  }
  z.comm = ctx.comm();
  if (z.prm.shape != "box" && z.prm.centre.size() < dim)
    throw InvalidInput("Particles/Centre", "needs one coordinate per dimension",
                       std::to_string(dim) + " comma-separated values [m]");
  auto options = z.method->neighbor_options(z.prm.spacing);
  // Distributed on more than one rank (particle_zone.h). Ghosts reach two search radii (δ plus
  // the partial-volume shell), so the first-layer ghosts' rows are whole: for bond-based PD's
  // surface correction, for NOSB-PD's families.
  const bool distribute = ctx.n_ranks() > 1;
  if (distribute)
    z.particles = z.distributed_body(2.0 * (options.horizon + z.prm.spacing) * (1 + 1e-9));
  else
    z.particles = z.body();
  z.particles.set_density(z.law.density);
  for (std::size_t k = 0; k < z.prm.cracks.size(); ++k) {
    const std::string where = "Particles/Crack " + std::to_string(k + 1) + "/Corners";
    const auto c = parse_crack_corners(z.prm.cracks[k], where, dim);
    if (dim == 2 && c.size() == 4)
      options.pre_cracks.push_back(meshfree::PreCrack<dim>::segment(
          dealii::Point<dim>(c[0], c[1]), dealii::Point<dim>(c[2], c[3])));
    else if (dim == 3 && c.size() == 12) {
      dealii::Point<dim> p[4];
      for (unsigned int v = 0; v < 4; ++v)
        for (unsigned int d = 0; d < dim; ++d)
          p[v][d] = c[3 * v + d];
      options.pre_cracks.push_back(meshfree::PreCrack<dim>::quadrilateral(p[0], p[1], p[2], p[3]));
    } else
      throw InvalidInput(where, "wrong number of coordinates",
                         dim == 2 ? "two points 'x1,y1; x2,y2'" : "four points of 3 coordinates");
  }
  if (z.partition) { // rows for owned particles and the ghosts bonded to them, checked for owned
    options.rows_around_first = z.partition->n_owned();
    options.surface_checked_particles = z.partition->n_owned();
  }
  z.collectively([&] { z.bonds = meshfree::NeighborSearch<dim>(options).build(z.particles); });
  if (z.partition) {
    // Forces are summed for owned particles only; a NOSB-PD force also gathers the families
    // of the first-layer ghosts, so their rows stay (and are updated the same way on every
    // rank that holds them: the same displacements, the same breaks).
    if (!z.method->needs_neighbour_rows())
      z.bonds.keep_rows(z.partition->n_owned());
    z.drop_unbonded_ghosts(); // collective: keep_ghosts rebuilds the exchange
    z.method->set_first_ghost(z.partition->n_owned());
    // An SPG break is decided on both ends' positions u = Σ Ψ d, which only a rank holding
    // both rows whole can form, and it reshapes both rows, copies of which live on other
    // ranks: the owner of the end with the lower lattice id decides, and all ranks break
    // the decided pairs together (compute_forces).
    if (z.shares_breaks())
      z.method->set_break_decider([&z](unsigned int i, unsigned int j) {
        const auto& ids = z.partition->ids();
        return z.partition->is_owned(ids[i] < ids[j] ? i : j);
      });
  }
  z.broken_initially = std::size_t(z.sum(z.owned_broken_ends()));
  z.n_bonds_global = std::uint64_t(z.sum(z.owned_bond_ends())) / 2;
  z.n_global = std::uint64_t(z.sum(z.n_owned()));
  z.method->initialise(z.particles, z.bonds);
  z.stiffness_bound = z.method->stiffness_bound(z.particles, z.bonds);
  z.dt_stable = z.min(z.method->stable_time_step(z.particles, z.bonds, z.prm.time_step_safety));
  if (z.newton_steps && z.prm.integration == "quasi_static") {
    // Newton on the bond-based model; distributed, its tangent's rows are the owned particles
    // and its ghosts follow every update through the zone's exchange.
    const auto& model = dynamic_cast<const meshfree::BondBasedMethod<dim>&>(*z.method).model();
    z.newton = std::make_unique<meshfree::ImplicitStaticSolver<dim>>(z.newton_prm, model);
    if (z.partition)
      z.newton->set_distribution(z.partition->numbering(), [&z](meshfree::ParticleSet<dim>& p) {
        z.partition->update_ghosts(p.displacements());
      });
  }

  const char letters[] = {'x', 'y', 'z'};
  for (std::size_t k = 0; k < z.prm.regions.size(); ++k) {
    const auto& r = z.prm.regions[k];
    const std::string where = "Particles/Region " + std::to_string(k + 1);
    typename Impl::PrescribedRegion region;
    for (const auto& letter : dealii::Utilities::split_string_list(r.components, ',')) {
      const auto* pos = std::find(letters, letters + dim, letter.empty() ? ' ' : letter[0]);
      if (letter.size() != 1 || pos == letters + dim)
        throw InvalidInput(where + "/Components", "unknown component '" + letter + "'",
                           dim == 2 ? "x,y" : "x,y,z");
      region.components.push_back(pos - letters);
    }
    region.values = parse_expressions<dim>(r.values, where + "/Values", region.components.size(),
                                           true, "[m], one per component");
    for (unsigned int i = 0; i < z.n_owned(); ++i) {
      const auto& x = z.particles.reference_position(i);
      bool inside = true;
      for (unsigned int d = 0; d < dim; ++d)
        inside = inside && x[d] >= r.lower[d] && x[d] <= r.upper[d];
      if (inside && !r.radial_range.empty()) {
        const double radius = std::hypot(x[0] - z.prm.centre[0], x[1] - z.prm.centre[1]);
        inside = radius >= r.radial_range[0] && radius <= r.radial_range[1];
      }
      if (inside) {
        region.particles.push_back(i);
        for (const unsigned int c : region.components)
          z.particles.set_fixed(i, c);
      }
    }
    if (z.sum(region.particles.size()) == 0)
      throw InvalidInput(where, "holds no particle", "a box that contains lattice points");
    z.regions.push_back(std::move(region));
  }
  z.verlet = std::make_unique<meshfree::VelocityVerlet<dim>>(
      [&z](meshfree::ParticleSet<dim>& p) { z.compute_forces(p); });
  z.prescribe(0.0);
  z.collectively([&z] { z.set_initial_velocity(); });
  if (z.prm.integration == "explicit") {
    if (z.partition)
      z.energy.set_counted(z.partition->n_owned());
    if (z.account)
      z.energy.start(z.particles, z.internal_energy(z.particles));
    z.verlet->initialise(z.particles); // forces and accelerations at t = 0
  }
  ctx.log() << "  particles: " << n_global_particles() << " on a lattice of spacing "
            << z.prm.spacing << " m, " << z.n_bonds_global << " bonds (" << z.broken_initially / 2
            << " cut by pre-cracks), stable step " << z.dt_stable << " s, method "
            << z.method->name() << ", material " << z.law.describe() << "\n";
  if (z.partition) {
    const double owned = z.partition->n_owned(), held = z.particles.size();
    ctx.log() << "  distributed over " << ctx.n_ranks() << " ranks on "
              << z.partition->n_background_cells()
              << " p4est background cells weighted by their particles: owned particles per "
                 "rank max/mean "
              << z.partition->load_imbalance()
              << " (equal cells: " << z.partition->load_imbalance_unweighted()
              << "), ghosts per owned " << (z.sum(held) - z.sum(owned)) / z.sum(owned) << "\n";
  }
  if (!z.damage) {
    const std::string criteria = z.method->user_failure_criteria();
    if (!criteria.empty())
      ctx.log() << "  Effects/Damage = false: no bond breaks, so the particles' failure "
                   "criteria are not applied ("
                << criteria << ")\n";
  }
  for (const auto& message : take_messages())
    ctx.log() << "  " << message << "\n";
}

template <int dim>
std::array<double, 3> ParticleZone<dim>::step_cut_state() const {
  return {{impl_->sub_step, double(impl_->sub_steps_converged), double(impl_->step_cuts)}};
}

template <int dim>
void ParticleZone<dim>::restore_step_cut_state(const std::array<double, 3>& state) {
  impl_->sub_step = state[0] > 0 && std::isfinite(state[0]) ? state[0] : 0.0;
  impl_->sub_steps_converged = state[1] >= 0 && state[1] < 3 ? unsigned(state[1]) : 0u;
  impl_->step_cuts = state[2] >= 0 && state[2] < 1e9 ? unsigned(state[2]) : 0u;
}

template <int dim>
std::vector<std::string> ParticleZone<dim>::take_messages() {
  Impl& z = *impl_;
  std::vector<std::string> mine = z.method->take_messages();
  mine.insert(mine.end(), z.messages.begin(), z.messages.end()); // every rank's alike
  z.messages.clear();
  if (!z.partition)
    return mine;
  // A distributed zone's particles are reported by their owners, on any rank; a message every
  // rank made (about the method, not a particle) is said once.
  const auto all = dealii::Utilities::MPI::gather(z.comm, mine, 0);
  std::vector<std::string> messages;
  std::map<std::string, std::vector<unsigned int>> ranks_of;
  for (unsigned int r = 0; r < all.size(); ++r)
    for (const auto& m : all[r]) {
      auto& ranks = ranks_of[m];
      if (ranks.empty())
        messages.push_back(m);
      ranks.push_back(r);
    }
  for (auto& m : messages) {
    const auto& ranks = ranks_of[m];
    if (ranks.size() == 1)
      m += " (MPI rank " + std::to_string(ranks[0]) + ")";
    else if (ranks.size() < all.size()) {
      m += " (MPI ranks";
      for (const unsigned int r : ranks)
        m += " " + std::to_string(r);
      m += ")";
    }
  }
  return messages;
}

template <int dim>
bool ParticleZone<dim>::advance_to(double time, const std::function<bool(double)>& stop) {
  Impl& z = *impl_;
  struct Clock { // adds the wall time of this call to advance_seconds, however it returns
    double& total;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ~Clock() {
      total += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  } clock{z.advance_seconds};
  if (z.prm.integration == "quasi_static") {
    meshfree::AdaptiveDynamicRelaxation<dim> adr(
        z.adr_prm, [&z](meshfree::ParticleSet<dim>& p) { z.compute_forces(p); });
    if (z.partition) // sums over the owned particles of all ranks
      adr.set_distribution({z.n_owned(),
                            [&z](std::vector<double>& values) {
                              MPI_Allreduce(MPI_IN_PLACE, values.data(), int(values.size()),
                                            MPI_DOUBLE, MPI_SUM, z.comm);
                            },
                            [&z](const std::function<void()>& f) { z.collectively(f); }});
    // A relaxation that does not converge is not carried on from: the state at the start of
    // the (sub-)step is restored and the load applied in two halves, as in coupled runs
    // (Simulation::coupled_relaxation). The sub-step doubles after two converged ones and
    // carries over to the next step.
    const double span = time - z.time;
    double sub = z.sub_step > 0 ? std::min(z.sub_step, span) : span;
    unsigned int cuts = 0;
    while (z.time < time - 1e-9 * span) {
      const double target = time - z.time <= sub * (1 + 1e-9) ? time : z.time + sub;
      std::optional<typename Impl::Snapshot> snapshot;
      if (cuts < z.max_step_cuts) // the last attempt allowed is never undone
        snapshot = z.snapshot();
      z.prescribe(target);
      // A failure met on every rank of the zone (a non-finite force, a law that fails at a
      // particle) ends the attempt like a relaxation that does not converge: undone and cut.
      // One rank of a distributed zone alone: the others cannot follow an undo.
      typename meshfree::AdaptiveDynamicRelaxation<dim>::Result result;
      std::optional<NumericalFailure> failure;
      try {
        result = z.newton                 ? z.newton_solve()
                 : z.break_at_equilibrium ? z.relax_at_equilibrium(adr)
                                          : adr.solve(z.particles, z.stiffness_bound);
      } catch (const NumericalFailure& e) {
        if (z.partition && !e.collective())
          throw;
        failure = e;
        result.converged = false;
        result.iterations = adr.last_iterations() +
                            (!z.newton && z.break_at_equilibrium ? z.earlier_pass_iterations : 0);
      }
      z.relaxation_iterations += result.iterations;
      if (!result.converged) {
        const std::string cut_note =
            cuts > 0 ? " after " + std::to_string(cuts) + " step cuts" : std::string();
        if (cuts >= z.max_step_cuts && failure)
          throw NumericalFailure(failure->what_failed() + cut_note,
                                 failure->location() +
                                     ", particle zone, t = " + significant(target, 6) + " s",
                                 failure->hint() + "; or cut the step further: raise "
                                                   "Particles/Quasi-static/Step cuts or take "
                                                   "more, smaller steps");
        const std::string solver = z.newton ? "Newton" : "dynamic relaxation";
        if (cuts >= z.max_step_cuts)
          throw NumericalFailure(
              solver + " did not converge (relative residual " +
                  significant(result.relative_residual) + " after " +
                  std::to_string(result.iterations) + " iterations" +
                  (cuts > 0 ? ", " + std::to_string(cuts) + " step cuts" : std::string()) + ")",
              "particle zone, t = " + significant(target, 6) + " s",
              std::string("raise Particles/Quasi-static/") +
                  (z.newton ? "Newton iterations (or Breaking passes)" : "Maximum iterations") +
                  " or Step cuts, or take more, smaller steps");
        const double from = z.time;
        z.restore(*snapshot);
        if (z.newton) // the restore may bring back bonds the tangent's pattern dropped
          z.newton->reset_pattern();
        sub = (target - from) / 2;
        ++cuts;
        ++z.step_cuts;
        z.sub_steps_converged = 0;
        z.messages.push_back(
            "t = " + significant(target, 6) + " s: " + (z.newton ? "Newton " : "relaxation ") +
            (failure ? "failed: " + failure->what_failed() + " (" + failure->location() + ")"
                     : "not converged (relative residual " + significant(result.relative_residual) +
                           " after " + std::to_string(result.iterations) + " iterations)") +
            "; state of t = " + significant(from, 6) + " s restored, load step cut to " +
            significant(sub) + " s");
        continue;
      }
      z.method->commit_state();
      z.time = target;
      if (sub < span && ++z.sub_steps_converged >= 2) {
        sub = std::min(2 * sub, span);
        z.sub_steps_converged = 0;
      }
    }
    z.sub_step = sub;
    return true;
  }
  while (z.time < time * (1 - 1e-12)) {
    if (stop && stop(z.time))
      return false;
    const double dt = std::min(z.dt_stable, time - z.time);
    if (z.account)
      z.energy.before_step(z.particles);
    z.prescribe(z.time + dt);
    z.verlet->step(z.particles, dt);
    z.method->commit_state();
    double damped = 0; // the kinetic energy the decay takes out [J]
    if (z.prm.damping > 0) {
      const double factor = std::exp(-z.prm.damping * dt);
      for (unsigned int i = 0; i < z.particles.size(); ++i) {
        damped += 0.5 * z.particles.mass(i) * (1 - factor * factor) *
                  z.particles.velocity(i).norm_square();
        z.particles.velocity(i) *= factor;
      }
    }
    for (const auto& v : z.particles.velocities())
      z.max_speed = std::max(z.max_speed, v.norm());
    // A broken bond can stiffen a NOSB-PD family (its shape tensor shrinks), a short-range
    // pair that engages adds a spring, so the stable step may only get smaller after either
    // (bond-based PD: its bound never falls). Distributed: every rank takes the step of the run
    // (one reduction a step).
    const bool local = z.broke_since_step_check > 0 || z.method->stiffness_bound_stale();
    const bool broke = z.partition ? dealii::Utilities::MPI::logical_or(local, z.comm) : local;
    if (broke) {
      z.dt_stable =
          std::min(z.dt_stable,
                   z.min(z.method->stable_time_step(z.particles, z.bonds, z.prm.time_step_safety)));
      z.broke_since_step_check = 0;
    }
    z.time += dt;
    ++z.explicit_steps;
    if (z.account)
      z.energy.after_step(z.particles, z.time, dt, damped);
  }
  return true;
}

template <int dim>
void ParticleZone<dim>::add_history(std::vector<std::pair<std::string, double>>& row) {
  Impl& z = *impl_;
  z.method->update_damage(z.particles, z.bonds);
  double max_damage = 0;
  for (unsigned int i = 0; i < z.n_owned(); ++i) // ghosts have no rows here
    max_damage = std::max(max_damage, z.particles.damage(i));
  row.emplace_back("particle_kinetic_energy", z.sum(z.particles.kinetic_energy()));
  row.emplace_back("particle_strain_energy", z.sum(z.method->strain_energy(z.particles, z.bonds)));
  row.emplace_back("broken_bonds", (z.sum(z.owned_broken_ends()) - z.broken_initially) / 2);
  row.emplace_back("max_damage", z.max(max_damage));
  row.emplace_back("fragments", z.fragments().fragments);
  if (const auto* contacts = z.method->short_range_contacts()) {
    // Owned rows only (a distributed zone's ghosts are their owners' to count).
    double n = 0;
    for (unsigned int i = 0; i < z.n_owned() && i < contacts->size(); ++i)
      n += (*contacts)[i];
    row.emplace_back("short_range_contacts", z.sum(n));
  }
  if (z.prm.reaction_region > 0) {
    const auto r = z.reaction();
    const char* names[] = {"particle_reaction_x", "particle_reaction_y", "particle_reaction_z"};
    for (unsigned int d = 0; d < dim; ++d)
      row.emplace_back(names[d], r[d]);
  }
}

template <int dim>
std::size_t ParticleZone<dim>::n_bonds() const {
  return impl_->n_bonds_global;
}

template <int dim>
dealii::Tensor<1, dim> ParticleZone<dim>::reaction() const {
  return impl_->reaction();
}

template <int dim>
bool ParticleZone<dim>::has_reaction() const {
  return impl_->prm.reaction_region > 0;
}

template <int dim>
bool ParticleZone<dim>::distributed() const {
  return impl_->partition != nullptr;
}

template <int dim>
bool ParticleZone<dim>::is_owned(unsigned int i) const {
  return i < impl_->n_owned();
}

template <int dim>
const std::vector<std::uint64_t>* ParticleZone<dim>::global_ids() const {
  return impl_->partition ? &impl_->partition->ids() : nullptr;
}

template <int dim>
std::uint64_t ParticleZone<dim>::n_global_particles() const {
  return impl_->n_global;
}

template <int dim>
std::size_t ParticleZone<dim>::memory_bytes() const {
  const Impl& z = *impl_;
  std::size_t bytes = z.particles.memory_bytes() + z.bonds.memory_bytes() +
                      z.method->memory_bytes() + z.stiffness_bound.capacity() * sizeof(double) +
                      z.forces_before.capacity() * sizeof(dealii::Tensor<1, dim>);
  for (const auto& r : z.regions)
    bytes += r.particles.capacity() * sizeof(unsigned int);
  return bytes + (z.partition ? z.partition->memory_bytes() : 0);
}

template <int dim>
double ParticleZone<dim>::stable_time_step() const {
  return impl_->dt_stable;
}

template <int dim>
void ParticleZone<dim>::add_figures(RunContext& ctx) const {
  const Impl& z = *impl_;
  Summary& s = ctx.summary();
  const std::string per = dim == 2 ? "/m" : "";
  s.set_figure("particles", double(n_global_particles()), "-");
  s.set_figure("particle_spacing_m", z.prm.spacing, "m");
  unsigned int free = 0; // the particles the method solves for (no prescribed component)
  for (unsigned int i = 0; i < z.n_owned(); ++i)
    free += !z.particles.is_fixed(i);
  s.set_figure("free_particles", z.sum(free), "-");
  s.set_figure("bonds", double(z.n_bonds_global), "-");
  s.set_figure("broken_bonds", (z.sum(z.owned_broken_ends()) - z.broken_initially) / 2, "-");
  s.set_figure("particle_strain_energy", z.sum(z.method->strain_energy(z.particles, z.bonds)),
               "J" + per);
  s.set_figure("particle_kinetic_energy", z.sum(z.particles.kinetic_energy()), "J" + per);
  if (z.method->has_plastic_work()) // laws with stored energy W(state)
    s.set_figure("particle_plastic_work", z.sum(z.plastic_work(z.particles)), "J" + per);
  s.set_figure("particle_stable_time_step", z.dt_stable, "s");
  // The particle data of the rank holding the most (particle_zone.h: memory_bytes).
  s.set_figure("particle_memory_per_rank_max_bytes",
               dealii::Utilities::MPI::max(double(memory_bytes()), ctx.comm()), "B");
  s.set_figure("particle_ranks", z.partition ? ctx.n_ranks() : 1, "-");
  if (z.partition) { // owned particles of the busiest rank over the mean (zone_partition.h)
    s.set_figure("particle_load_imbalance", z.partition->load_imbalance(), "-");
    s.set_figure("particle_load_imbalance_unweighted", z.partition->load_imbalance_unweighted(),
                 "-");
  }
  s.set_figure("particle_advance_time_s", z.max(z.advance_seconds), "s");
  const auto pieces = z.fragments();
  s.set_figure("fragments", pieces.fragments, "-");
  s.set_figure("isolated_particles", pieces.isolated, "-");
  s.set_figure("largest_fragment_particles", pieces.largest, "-");
  if (z.method->carries_material_state()) {
    // Fracture damage D_f (NOSB-PD: stress released at bond breaks; 0 for other methods):
    // the largest, and the volume share of particles past one half.
    double max_df = 0, damaged_volume = 0, volume = 0;
    for (unsigned int i = 0; i < z.n_owned(); ++i) {
      const double df = z.method->particle_state(i).fracture_damage;
      max_df = std::max(max_df, df);
      volume += z.particles.volume(i);
      damaged_volume += df > 0.5 ? z.particles.volume(i) : 0.0;
    }
    s.set_figure("max_fracture_damage", z.max(max_df), "-");
    s.set_figure("fracture_damaged_volume_fraction", z.sum(damaged_volume) / z.sum(volume), "-");
  }
  if (z.prm.integration == "explicit") {
    s.set_figure("particle_explicit_steps", z.explicit_steps, "-");
    s.set_figure("max_particle_speed", z.max(z.max_speed), "m/s");
  } else {
    s.set_figure("relaxation_iterations", z.relaxation_iterations, "iterations");
    s.set_figure("relaxation_step_cuts", z.step_cuts, "-");
  }
  if (z.prm.reaction_region > 0)
    s.set_figure("particle_reaction_norm", z.reaction().norm(), dim == 2 ? "N/m" : "N");
  (void)per;
}

template <int dim>
void ParticleZone<dim>::set_energy_account(bool on) {
  if (on && impl_->prm.integration != "explicit")
    throw InvalidInput(
        "Simulation/Energy account",
        "true, but the account follows explicit steps and Particles/Integration is " +
            impl_->prm.integration,
        "false, or Particles/Integration = explicit");
  impl_->account = on;
}

template <int dim>
bool ParticleZone<dim>::energy_account_restored() const {
  return impl_->account_restored;
}

template <int dim>
fem::EnergyBalance ParticleZone<dim>::energy_balance() const {
  fem::EnergyBalance b = impl_->energy.balance();
  // A restart that could not continue the account (energy_account_restored) has none: NaN.
  b.valid = b.valid && impl_->account_restored;
  if (!impl_->partition)
    return b;
  // Each rank's account covers its owned particles and bond rows: the terms add up.
  for (double* term :
       {&b.external_work, &b.strain_energy, &b.kinetic_energy, &b.kinetic_energy_central,
        &b.fracture_dissipation, &b.damping_dissipation, &b.initial_energy})
    *term = impl_->sum(*term);
  b.valid = !dealii::Utilities::MPI::logical_or(!b.valid, impl_->comm);
  return b;
}

template <int dim>
std::string ParticleZone<dim>::write_output(const std::string& directory,
                                            unsigned int cycle) const {
  const std::string base = "particles_" + dealii::Utilities::int_to_string(cycle, 4);
  // A method with material state adds its plastic strain and fracture damage D_f (the share
  // of stress a NOSB-PD family lost at bond breaks) per particle, on a copy of the set.
  std::optional<meshfree::ParticleSet<dim>> with_state;
  if (impl_->method && impl_->method->generalised_displacements()) {
    with_state.emplace(impl_->particles);
    with_state->displacements() = physical_displacements();
  }
  if (impl_->method && impl_->method->carries_material_state()) {
    if (!with_state)
      with_state.emplace(impl_->particles);
    auto& eps = with_state->add_scalar_field("equivalent_plastic_strain");
    auto& df = with_state->add_scalar_field("fracture_damage");
    for (unsigned int i = 0; i < impl_->n_owned(); ++i) {
      const materials::MaterialState st = impl_->method->particle_state(i);
      eps[i] = st.equivalent_plastic_strain;
      df[i] = st.fracture_damage;
    }
  }
  const meshfree::ParticleSet<dim>& particles = with_state ? *with_state : impl_->particles;
  if (!impl_->partition) {
    meshfree::write_particles_vtu(particles, directory + "/" + base + ".vtu");
    return base + ".vtu";
  }
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(impl_->comm),
                     ranks = dealii::Utilities::MPI::n_mpi_processes(impl_->comm);
  const auto piece = [&](unsigned int r) {
    return base + "." + dealii::Utilities::int_to_string(r, 4) + ".vtu";
  };
  meshfree::write_particles_vtu(particles, directory + "/" + piece(rank), impl_->n_owned());
  if (rank == 0) {
    std::vector<std::string> pieces;
    for (unsigned int r = 0; r < ranks; ++r)
      pieces.push_back(piece(r));
    meshfree::write_particles_pvtu(particles, directory + "/" + base + ".pvtu", pieces);
  }
  return base + ".pvtu";
}

namespace {
// Last entry of a particle checkpoint ("SPZ-END"): a file that ends before it was cut.
constexpr std::uint64_t checkpoint_end_tag = 0x444e452d5a5053ull;
// After the stable step ("SPZ-WP"): the account's stored energy is measured as this version
// measures it (see save() and load()).
constexpr std::uint64_t account_measure_tag = 0x50572d5a5053ull;
} // namespace

template <int dim>
void ParticleZone<dim>::save(const std::string& file) const {
  impl_->collectively([&] { // a rank that cannot write stops all of them
    const Impl& z = *impl_;
    const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(z.comm),
                       ranks = dealii::Utilities::MPI::n_mpi_processes(z.comm);
    std::ofstream out(z.partition ? file + "." + std::to_string(rank) : file, std::ios::binary);
    const auto write = [&out](const void* data, std::size_t bytes) {
      out.write(static_cast<const char*>(data), bytes);
    };
    const std::uint64_t n = z.particles.size(), nb = z.bonds.n_bonds();
    write(&n, sizeof n);
    write(&nb, sizeof nb);
    if (z.partition) { // the part of a distributed zone: restart on the same ranks only
      const std::uint32_t r = rank, rs = ranks;
      write(&r, sizeof r);
      write(&rs, sizeof rs);
    }
    write(&z.time, sizeof z.time);
    write(&z.explicit_steps, sizeof z.explicit_steps);
    write(&z.relaxation_iterations, sizeof z.relaxation_iterations);
    for (const auto* field :
         {&z.particles.displacements(), &z.particles.velocities(), &z.particles.accelerations()})
      write(field->data(), field->size() * sizeof(dealii::Tensor<1, dim>));
    write(z.bonds.broken.data(), nb);
    z.method->save(out);
    z.energy.save(out); // the account and the run's top speed, so a restart continues them
    out.write(reinterpret_cast<const char*>(&z.max_speed), sizeof z.max_speed);
    // The stepping time so far, so particle_advance_time_s covers the whole run after a restart.
    out.write(reinterpret_cast<const char*>(&z.advance_seconds), sizeof z.advance_seconds);
    // The forces of the last pass, which the restart keeps instead of its own pass: with a
    // history-dependent law that pass would start from the history the last one committed and
    // return-map the same F once more (equal only to round-off, ~1e-15).
    write(z.particles.forces().data(), z.particles.size() * sizeof(dealii::Tensor<1, dim>));
    write(&checkpoint_end_tag, sizeof checkpoint_end_tag); // a file cut inside the forces shows
    // The stable step as breaks have shrunk it (it only falls during a run): a restart takes
    // the same steps as the uninterrupted run. After the end tag: older files end without it.
    write(&z.dt_stable, sizeof z.dt_stable);
    // Last: the account's stored energy is this version's measure (the stored energy of J2
    // laws from their state plus their plastic work, SPG's stabilisation energy included).
    write(&account_measure_tag, sizeof account_measure_tag);
    if (!out)
      throw std::runtime_error("cannot write particle checkpoint " + file);
  });
}

template <int dim>
void ParticleZone<dim>::load(const std::string& file) {
  Impl& z = *impl_;
  std::vector<dealii::Tensor<1, dim>> forces, accelerations; // of the last pass, if saved
  // Every check fails on all ranks alike; the force pass below is collective.
  z.collectively([&] {
    const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(z.comm),
                       ranks = dealii::Utilities::MPI::n_mpi_processes(z.comm);
    const std::string part = z.partition ? file + "." + std::to_string(rank) : file;
    std::ifstream in(part, std::ios::binary);
    if (!z.partition && !in)
      throw InvalidInput(part,
                         "no particle checkpoint (a distributed zone writes one file per rank, " +
                             file + ".<rank>)",
                         "a restart on the number of MPI ranks that wrote the checkpoint");
    if (z.partition && !in && std::ifstream(file))
      throw InvalidInput(part,
                         "no particle checkpoint for rank " + std::to_string(rank) + ", but " +
                             file +
                             " holds a whole zone: it was written by a run on one rank (or by "
                             "an earlier version, which held NOSB-PD and quasi-static zones "
                             "whole on every rank)",
                         "a restart on one rank, as the run that wrote it");
    if (z.partition && !in)
      throw InvalidInput(part,
                         "no particle checkpoint for rank " + std::to_string(rank) +
                             ": the checkpoint was written by a run on another number of ranks",
                         "a restart on the number of MPI ranks that wrote the checkpoint");
    const auto read = [&in](void* data, std::size_t bytes) {
      in.read(static_cast<char*>(data), bytes);
    };
    std::uint64_t n = 0, nb = 0;
    read(&n, sizeof n);
    read(&nb, sizeof nb);
    std::uint32_t saved_rank = rank, saved_ranks = ranks;
    if (z.partition) {
      read(&saved_rank, sizeof saved_rank);
      read(&saved_ranks, sizeof saved_ranks);
    }
    if (!in || saved_rank != rank || saved_ranks != ranks)
      throw InvalidInput(part,
                         "particle checkpoint written by a run on " + std::to_string(saved_ranks) +
                             " rank(s), not distributed as this run (" + std::to_string(ranks) +
                             " ranks)",
                         "a restart on the number of MPI ranks that wrote the checkpoint");
    if (n != z.particles.size() || nb != z.bonds.n_bonds())
      throw InvalidInput(part, "particle checkpoint does not match the scene's particle zone",
                         "the checkpoint of this run, unchanged Particles parameters");
    read(&z.time, sizeof z.time);
    read(&z.explicit_steps, sizeof z.explicit_steps);
    read(&z.relaxation_iterations, sizeof z.relaxation_iterations);
    for (auto* field :
         {&z.particles.displacements(), &z.particles.velocities(), &z.particles.accelerations()})
      read(field->data(), field->size() * sizeof(dealii::Tensor<1, dim>));
    read(z.bonds.broken.data(), nb);
    if (!in)
      throw InvalidInput(file, "particle checkpoint is truncated", "a complete checkpoint");
    // The file comes from outside (the manifest vouches for it only where there is one): every
    // value read must be one a run writes, or the restart would carry NaN or a bond that is
    // neither intact nor broken into its first step.
    const auto bad = [&](const std::string& what) {
      return InvalidInput(part, "particle checkpoint holds " + what,
                          "the checkpoint as the run wrote it; restart from an earlier copy of "
                          "the run directory, or start the run again");
    };
    if (!(std::isfinite(z.time) && z.time >= 0))
      throw bad("the time " + significant(z.time) + " s (a finite time >= 0)");
    const auto check_finite = [&](const std::vector<dealii::Tensor<1, dim>>& field,
                                  const char* name) {
      for (std::size_t i = 0; i < field.size(); ++i)
        for (unsigned int d = 0; d < dim; ++d)
          if (!std::isfinite(field[i][d]))
            throw bad(std::string("a non-finite ") + name + " of particle " + std::to_string(i));
    };
    check_finite(z.particles.displacements(), "displacement");
    check_finite(z.particles.velocities(), "velocity");
    check_finite(z.particles.accelerations(), "acceleration");
    for (std::size_t k = 0; k < nb; ++k)
      if (z.bonds.broken[k] > 1)
        throw bad("the state " + std::to_string(int(z.bonds.broken[k])) + " of bond " +
                  std::to_string(k) + " (0 intact, 1 broken)");
    z.method->initialise(z.particles, z.bonds); // families from the restored intact bonds
    try { // the method's and the account's readers name their part; this adds the file
      z.method->load(in);
      z.account_restored = z.energy.load(in);
    } catch (const InvalidInput& e) {
      throw InvalidInput(part + " (" + e.where() + ")", e.problem(), e.allowed());
    }
    if (in.read(reinterpret_cast<char*>(&z.max_speed), sizeof z.max_speed) &&
        !(std::isfinite(z.max_speed) && z.max_speed >= 0))
      throw bad("the run's top speed " + significant(z.max_speed) + " m/s (finite, >= 0)");
    double seconds = 0; // absent from checkpoints written before it was kept
    if (in.read(reinterpret_cast<char*>(&seconds), sizeof seconds)) {
      if (!(std::isfinite(seconds) && seconds >= 0))
        throw bad("the stepping time " + significant(seconds) + " s (finite, >= 0)");
      z.advance_seconds = seconds;
    }
    forces.resize(z.particles.size());
    in.read(reinterpret_cast<char*>(forces.data()), forces.size() * sizeof(forces[0]));
    if (in.gcount() == 0)
      forces.clear(); // a checkpoint written before they were kept
    else {
      std::uint64_t tag = 0;
      if (!in || !in.read(reinterpret_cast<char*>(&tag), sizeof tag) || tag != checkpoint_end_tag)
        throw InvalidInput(part, "particle checkpoint is truncated (it ends inside the forces)",
                           "a complete checkpoint");
      check_finite(forces, "force");
      // Absent from older checkpoints; where present, a step a run can have taken.
      double dt_stable = 0;
      if (in.read(reinterpret_cast<char*>(&dt_stable), sizeof dt_stable)) {
        if (!(dt_stable > 0)) // +inf: a zone without particles
          throw bad("the stable time step " + significant(dt_stable) + " s (> 0)");
        z.dt_stable = dt_stable;
      }
    }
    std::uint64_t account_tag = 0;
    const bool tagged = in.read(reinterpret_cast<char*>(&account_tag), sizeof account_tag) &&
                        account_tag == account_measure_tag;
    // Earlier versions measured the stored energy of NOSB-PD and SPG particles otherwise (the
    // path integral for J2 laws, SPG without its stabilisation energy): continued, the balance
    // would jump by the difference at the restart (the caller warns, as for a checkpoint
    // without an account). Bond-based PD's measure has not changed.
    if (!tagged && z.method->carries_material_state())
      z.account_restored = false;
    accelerations = z.particles.accelerations();
  });
  // The pass refreshes the method's own per-pass data (deformation gradients for output, the
  // trial history the next step replaces); the saved forces, where present, then stand.
  z.passes_break = false;
  z.verlet->initialise(z.particles);
  z.passes_break = true;
  z.method->take_messages(); // families lost before the checkpoint were reported then
  if (!forces.empty()) {
    z.particles.forces() = forces;
    z.particles.accelerations() = accelerations;
  }
}

template <int dim>
const meshfree::ParticleSet<dim>& ParticleZone<dim>::particles() const {
  return impl_->particles;
}

template <int dim>
std::vector<dealii::Tensor<1, dim>> ParticleZone<dim>::physical_displacements() const {
  return impl_->method ? impl_->method->physical_displacements(impl_->particles)
                       : impl_->particles.displacements();
}

template class ParticleZone<2>;
template class ParticleZone<3>;

} // namespace spinesim::applications
