// The `ghost_exchange` benchmark scenario: the cost of refreshing the ghosts of a distributed
// particle zone by the zone's own exchange (a Trilinos import over lattice ids, the plan made
// once; applications/simulation/zone_partition.h) against deal.II's
// Particles::ParticleHandler (exchange_ghost_particles once, then update_ghost_particles with
// the displacement as dim properties), for the same lattice, background cells and ghost
// reach (docs/scaling.md). Each side counts the same work: write the owned particles' values,
// exchange, read the ghosts' values.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/simulation/zone_partition.h"
#include "base/exceptions.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/particles/particle_handler.h>

#include <chrono>
#include <cmath>

namespace spinesim::applications {

using namespace framework;

namespace {

struct GhostExchangeParameters {
  double side = 0.03;    // [m]
  double spacing = 1e-3; // [m]
  double horizon_ratio = 3.015;
  unsigned int exchanges = 240;

  static void declare(dealii::ParameterHandler& prm) {
    prm.declare_entry("Side", "0.03", dealii::Patterns::Double(0),
                      "Edge of the cubic lattice block [m].");
    prm.declare_entry("Spacing", "1e-3", dealii::Patterns::Double(0), "Lattice spacing h [m].");
    prm.declare_entry("Horizon ratio", "3.015", dealii::Patterns::Double(1),
                      "Horizon over spacing; the ghost reach is 2 (δ + h), as in a zone [-].");
    prm.declare_entry("Exchanges", "240", dealii::Patterns::Integer(1),
                      "Ghost refreshes timed for each method [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    side = prm.get_double("Side");
    spacing = prm.get_double("Spacing");
    horizon_ratio = prm.get_double("Horizon ratio");
    exchanges = prm.get_integer("Exchanges");
    if (!(side > spacing))
      throw InvalidInput("Ghost exchange/Side", "not above the spacing",
                         "a block of several points");
  }
};

class GhostExchange : public Scenario {
 public:
  explicit GhostExchange(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Ghost exchange", prm_);
  }

  void run(RunContext& ctx) override {
    constexpr int dim = 3;
    using Clock = std::chrono::steady_clock;
    const MPI_Comm comm = ctx.comm();
    const double h = prm_.spacing, delta = prm_.horizon_ratio * h;
    const double reach = 2.0 * (delta + h) * (1 + 1e-9); // particle_zone.cc
    const dealii::Point<dim> lo, hi(prm_.side, prm_.side, prm_.side);
    ZonePartition<dim> zone(comm, lo, hi, h, reach, [](const dealii::Point<dim>&) { return true; });
    const unsigned int n_owned = zone.n_owned(), n = zone.points().size();
    std::vector<dealii::Tensor<1, dim>> u(n);
    double check_zone = 0;
    MPI_Barrier(comm);
    auto start = Clock::now();
    for (unsigned int s = 0; s < prm_.exchanges; ++s) {
      for (unsigned int i = 0; i < n_owned; ++i)
        u[i][0] = double(zone.ids()[i]) + s;
      zone.update_ghosts(u);
      for (unsigned int i = n_owned; i < n; ++i)
        check_zone += std::abs(u[i][0] - double(zone.ids()[i]) - s); // 0 when current
    }
    const double zone_s = std::chrono::duration<double>(Clock::now() - start).count();

    // The same particles in a ParticleHandler on the zone's background cells (the same
    // subdivision of the box: coarse cells at least one reach wide).
    dealii::parallel::distributed::Triangulation<dim> tria(comm);
    const unsigned int cells = std::max(1u, unsigned(std::floor(prm_.side / reach)));
    dealii::GridGenerator::subdivided_hyper_rectangle(tria, std::vector<unsigned int>(dim, cells),
                                                      lo, hi);
    dealii::MappingQ1<dim> mapping;
    dealii::Particles::ParticleHandler<dim> handler(tria, mapping, dim);
    handler.insert_particles(std::vector<dealii::Point<dim>>(
        zone.points().begin(), zone.points().begin() + n_owned)); // each rank its own
    MPI_Barrier(comm);
    start = Clock::now();
    handler.exchange_ghost_particles(true); // with the cache update_ghost_particles needs
    const double handler_setup_s = std::chrono::duration<double>(Clock::now() - start).count();
    double check_handler = 0;
    MPI_Barrier(comm);
    start = Clock::now();
    for (unsigned int s = 0; s < prm_.exchanges; ++s) {
      for (auto p = handler.begin(); p != handler.end(); ++p) {
        const auto values = p->get_properties();
        values[0] = s;
        values[1] = p->get_location()[0];
      }
      handler.update_ghost_particles();
      for (auto p = handler.begin_ghost(); p != handler.end_ghost(); ++p) {
        const auto values = p->get_properties();
        check_handler += std::abs(values[0] - s) + std::abs(values[1] - p->get_location()[0]);
      }
    }
    const double handler_s = std::chrono::duration<double>(Clock::now() - start).count();

    const auto max = [&](double x) { return dealii::Utilities::MPI::max(x, comm); };
    const auto sum = [&](double x) { return dealii::Utilities::MPI::sum(x, comm); };
    // Both checks sum exact differences between what a ghost holds and what its owner sent in
    // this refresh (integers, or a copied coordinate): anything but 0 is a stale or misplaced
    // ghost.
    const double off_zone = max(std::abs(check_zone)), off_handler = max(std::abs(check_handler));
    if (off_zone != 0 || off_handler != 0)
      throw NumericalFailure("a ghost value differs from its owner's (sum of differences: zone " +
                                 std::to_string(off_zone) + ", ParticleHandler " +
                                 std::to_string(off_handler) + ")",
                             "ghost_exchange benchmark",
                             "the exchange is broken; compare with tests/scenes/distributed.cmake");
    const double per_zone = max(zone_s) / prm_.exchanges,
                 per_handler = max(handler_s) / prm_.exchanges;
    Summary& s = ctx.summary();
    s.set_figure("particles", sum(n_owned), "-");
    s.set_figure("zone_ghosts", sum(n - n_owned), "-");
    s.set_figure(
        "particle_handler_ghosts",
        sum(handler.get_property_pool().n_registered_slots() - handler.n_locally_owned_particles()),
        "-");
    s.set_figure("zone_exchange_s", per_zone, "s");
    s.set_figure("particle_handler_exchange_s", per_handler, "s");
    s.set_figure("particle_handler_first_exchange_s", max(handler_setup_s), "s");
    s.set_figure("particle_handler_over_zone_time", per_handler / per_zone, "-");
    ctx.log() << "  " << sum(n_owned) << " particles on " << ctx.n_ranks()
              << " ranks; per exchange: zone (Trilinos import) " << per_zone * 1e6
              << " us, ParticleHandler " << per_handler * 1e6 << " us\n";
  }

 private:
  GhostExchangeParameters prm_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(ghost_exchange, "ghost_exchange",
                           "benchmark: a distributed particle zone's ghost exchange (Trilinos "
                           "import) against deal.II's ParticleHandler (docs/scaling.md).",
                           "particles:bond_based", create_scenario<GhostExchange>,
                           {"Ghost exchange", GhostExchangeParameters::declare})

} // namespace spinesim::applications
