#include "coupling/fem_particle_coupling.h"

#include "coupling/mls_fit.h"
#include "coupling/particle_record.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "base/scoped_time.h"
#include "fem/cell_indicators.h"
#include "fem/heat/heat_solver.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_output.h"

#include <deal.II/base/array_view.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/timer.h>
#include <deal.II/base/utilities.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/vector_tools.h>

#include <boost/serialization/string.hpp>
#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <unordered_map>

namespace spinesim::coupling {

using namespace dealii;

namespace {

std::vector<double> parse_doubles(const std::string& list, const std::string& where) {
  return parse_number_list(list, where, /*allow_empty=*/true);
}

// Uniform bins of the given size over a point set: candidates within one bin distance.
template <int dim>
class PointBins {
 public:
  PointBins(const std::vector<Point<dim>>& points, double size) : points_(points), size_(size) {
    for (unsigned int i = 0; i < points.size(); ++i)
      bins_[key(points[i])].push_back(i);
  }
  // Whether some point lies within `radius` of x.
  bool any_within(const Point<dim>& x, double radius) const {
    return !visit_within(x, radius, [](unsigned int) { return false; });
  }
  // Indices of points within `radius` of x.
  std::vector<unsigned int> within(const Point<dim>& x, double radius) const {
    std::vector<unsigned int> out;
    visit_within(x, radius, [&](unsigned int i) {
      out.push_back(i);
      return true;
    });
    return out;
  }

 private:
  std::array<long, 3> coords(const Point<dim>& x) const {
    std::array<long, 3> k{{0, 0, 0}};
    for (unsigned int d = 0; d < dim; ++d)
      k[d] = static_cast<long>(std::floor(x[d] / size_));
    return k;
  }
  static long long pack(const std::array<long, 3>& k) {
    return ((k[0] + (1L << 20)) << 42) ^ ((k[1] + (1L << 20)) << 21) ^ (k[2] + (1L << 20));
  }
  long long key(const Point<dim>& x) const { return pack(coords(x)); }
  // Calls visit(i) for the points within `radius` of x until it returns false; returns
  // whether every call returned true.
  template <class Visit>
  bool visit_within(const Point<dim>& x, double radius, Visit&& visit) const {
    const std::array<long, 3> k = coords(x);
    const int span = static_cast<int>(std::ceil(radius / size_));
    std::array<long, 3> o{};
    for (o[0] = -span; o[0] <= span; ++o[0])
      for (o[1] = -span; o[1] <= span; ++o[1])
        for (o[2] = (dim == 3 ? -span : 0); o[2] <= (dim == 3 ? span : 0); ++o[2]) {
          const auto it = bins_.find(pack({{k[0] + o[0], k[1] + o[1], k[2] + o[2]}}));
          if (it == bins_.end())
            continue;
          for (const unsigned int i : it->second)
            if (points_[i].distance(x) <= radius && !visit(i))
              return false;
        }
    return true;
  }
  const std::vector<Point<dim>>& points_;
  double size_;
  std::unordered_map<long long, std::vector<unsigned int>> bins_;
};

} // namespace

// ---------------------------------------------------------------- parameters

template <int dim>
void FemParticleCoupling<dim>::Parameters::declare(ParameterHandler& prm) {
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
                    "Quasi-static coupled runs (Mechanics/Time integration = quasi_static): "
                    "dynamic relaxation of each step ends when the free residual (FEM DoFs and "
                    "particles) is this fraction of the larger of the reactions and the largest "
                    "residual of the step [-].");
  prm.declare_entry("Relaxation max iterations", "200000", Integer(1),
                    "Quasi-static coupled runs: pseudo-time steps allowed per step before the "
                    "run stops as not converged [-].");
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
void FemParticleCoupling<dim>::Parameters::parse(ParameterHandler& prm, const std::string& method) {
  particles_per_direction = prm.get_integer("Particles per cell direction");
  ghost_layer = prm.get_double("Ghost layer");
  interface_radius = prm.get_double("Interface radius");
  time_step_safety = prm.get_double("Time step safety");
  all_particles = prm.get_bool("All particles");
  region_lower =
      parse_doubles(prm.get("Initial region lower corner"), "Coupling/Initial region lower corner");
  region_upper =
      parse_doubles(prm.get("Initial region upper corner"), "Coupling/Initial region upper corner");
  if (region_lower.size() != region_upper.size() ||
      (!region_lower.empty() && region_lower.size() < dim))
    throw InvalidInput("Coupling/Initial region lower corner",
                       "the two corners need " + std::to_string(dim) + " coordinates each",
                       "both empty, or both 'x,y" + std::string(dim == 3 ? ",z" : "") + "' [m]");
  principal_strain_threshold = prm.get_double("Principal strain threshold");
  plastic_strain_threshold = prm.get_double("Plastic strain threshold");
  min_jacobian_ratio = prm.get_double("Minimum Jacobian ratio");
  min_time_step = prm.get_double("Minimum time step");
  buffer = prm.get_double("Buffer");
  check_interval = prm.get_integer("Check interval");
  refine_lower = parse_doubles(prm.get("Refinement region lower corner"),
                               "Coupling/Refinement region lower corner");
  refine_upper = parse_doubles(prm.get("Refinement region upper corner"),
                               "Coupling/Refinement region upper corner");
  region_refinements = prm.get_integer("Region refinements");
  fracture_heat_fraction = prm.get_double("Fracture heat fraction");
  conserve_kinetic_energy = prm.get_bool("Conserve kinetic energy");
  relaxation_tolerance = prm.get_double("Relaxation tolerance");
  relaxation_max_iterations = prm.get_integer("Relaxation max iterations");
  if (refine_lower.size() != refine_upper.size() ||
      (!refine_lower.empty() && refine_lower.size() < dim))
    throw InvalidInput("Coupling/Refinement region lower corner",
                       "the two corners need " + std::to_string(dim) + " coordinates each",
                       "both empty, or both 'x,y" + std::string(dim == 3 ? ",z" : "") + "' [m]");
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
double FemParticleCoupling<dim>::ConversionReport::mass_change_relative() const {
  return std::abs(mass_after - mass_before) / std::max(mass_before, 1e-300);
}

template <int dim>
double FemParticleCoupling<dim>::ConversionReport::momentum_change_relative() const {
  return (momentum_after - momentum_before).norm() / std::max(momentum_before.norm(), 1e-300);
}

template <int dim>
double FemParticleCoupling<dim>::ConversionReport::kinetic_change_relative() const {
  return std::abs(kinetic_after - kinetic_before) / std::max(kinetic_before, 1e-300);
}

// ---------------------------------------------------------------- implementation state

template <int dim>
struct FemParticleCoupling<dim>::Impl {
  using DoFCell = typename DoFHandler<dim>::active_cell_iterator;
  struct InterfaceDof {
    types::global_dof_index dof;
    unsigned int component;
    std::vector<std::pair<unsigned int, double>> weights; // free particle, MLS shape value
  };
  struct FixedParticle {
    unsigned int particle;
    unsigned int slot; // Dirichlet slot of the solver's boundary conditions
  };
  QIterated<dim> points;                      // particle points of a cell (unit cell)
  FullMatrix<double> shape;                   // N_i(ξ_q), [q][i]
  std::map<std::string, DoFCell> owned_cells; // locally owned cells by CellId
  std::vector<DoFCell> owned_by_index; // locally owned cells by active cell index (else invalid)
  // The owned cells of the particle lattice's size, by active index: only these can convert
  // (the refinement box makes them).
  std::vector<DoFCell> lattice_cells;
  // Per particle: the active cell index of its host cell if this rank owns it, else -1 (the
  // CellId strings need a map lookup).
  std::vector<int> host_index;
  // Per particle: free at the last ghost-layer search (later ones are searched around).
  std::vector<std::uint8_t> free_searched;
  // Ghost particles hosted by locally owned cells: cell and its particle per point.
  std::vector<std::pair<DoFCell, std::vector<int>>> ghost_cells;
  std::vector<int> ghost_lids; // per ghost cell, its DoFs' local indices in the FEM vectors
  std::vector<std::pair<DoFCell, std::vector<int>>> free_cells; // for temperatures
  std::vector<InterfaceDof> interface;                          // ascending DoF order
  std::vector<double> interface_values;
  bool interface_registered = false; // the solver knows the interface DoFs
  std::vector<FixedParticle> fixed;
  std::vector<std::uint32_t> fixed_slots;  // per particle: Dirichlet slots of its cell
  std::vector<std::uint8_t> broken_before; // bond flags before a force pass (fracture heat)
  // Halo plan by rank: particles received from it (it owns them), particles sent to it.
  std::map<unsigned int, std::vector<unsigned int>> halo_recv, halo_send;
  // Every particle's bonds as last searched (pre-crack flags only) and the volumes they were
  // searched with: the next rebuild searches only rows that new or changed particles touch.
  meshfree::BondList<dim> searched_bonds;
  std::vector<double> searched_volumes;
  // Net accelerations of the free particle components at the last relaxation step [m/s²].
  std::vector<double> relax_acceleration;

  explicit Impl(unsigned int n) : points(QMidpoint<1>(), n) {}
};

template <int dim>
FemParticleCoupling<dim>::FemParticleCoupling(const Parameters& parameters,
                                              fem::MechanicsSolver<dim>& mechanics,
                                              const fem::HeatSolver<dim>* heat)
    : prm_(parameters), fem_(mechanics), heat_(heat),
      impl_(std::make_unique<Impl>(parameters.particles_per_direction)),
      particles_(1.0) { // 2-D coupled runs are per unit thickness (prepare())
  rank_ = Utilities::MPI::this_mpi_process(fem_.mpi_communicator());
  if (fem_.parameters().time_integration != "explicit" &&
      fem_.parameters().time_integration != "quasi_static")
    throw InvalidInput("Mechanics/Time integration",
                       "coupling runs explicit dynamics or quasi-static relaxation",
                       "explicit or quasi_static");
  if (fem_.parameters().kinematics != "small_strain" || fem_.parameters().fe_degree != 1)
    throw InvalidInput("Mechanics/Kinematics", "coupling needs small strain with Q1 elements",
                       "Kinematics = small_strain, Finite element degree = 1");
}

template <int dim>
FemParticleCoupling<dim>::~FemParticleCoupling() = default;

template <int dim>
void FemParticleCoupling<dim>::prepare_mesh(const Parameters& p,
                                            parallel::distributed::Triangulation<dim>& tria) {
  for (unsigned int r = 0; r < p.region_refinements && !p.refine_lower.empty(); ++r) {
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned()) {
        // Cells touching the box are refined (vertex test), so the box edge is resolved.
        bool touches = false;
        for (const unsigned int v : cell->vertex_indices()) {
          bool inside = true;
          for (unsigned int d = 0; d < dim; ++d)
            inside &= cell->vertex(v)[d] >= p.refine_lower[d] - 1e-12 &&
                      cell->vertex(v)[d] <= p.refine_upper[d] + 1e-12;
          touches |= inside;
        }
        if (touches)
          cell->set_refine_flag();
      }
    tria.execute_coarsening_and_refinement();
  }
  if (!p.all_particles)
    return;
  const unsigned int finest = Utilities::MPI::max(
      static_cast<unsigned int>(tria.n_global_levels() - 1), tria.get_communicator());
  for (;;) {
    bool any = false;
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned() && static_cast<unsigned int>(cell->level()) < finest) {
        cell->set_refine_flag();
        any = true;
      }
    if (!Utilities::MPI::logical_or(any, tria.get_communicator()))
      break;
    tria.execute_coarsening_and_refinement();
  }
}

template <int dim>
double FemParticleCoupling<dim>::horizon() const {
  return method_->neighbor_options(spacing_).horizon;
}

template <int dim>
void FemParticleCoupling<dim>::initialise() {
  prepare();
  const MPI_Comm comm = fem_.mpi_communicator();
  std::vector<std::string> initial;
  for (const auto& [id, cell] : impl_->owned_cells) {
    bool inside = prm_.all_particles;
    if (!inside && !prm_.region_lower.empty()) {
      inside = true;
      const Point<dim> c = cell->center();
      for (unsigned int d = 0; d < dim; ++d)
        inside &= c[d] >= prm_.region_lower[d] && c[d] <= prm_.region_upper[d];
    }
    if (inside)
      initial.push_back(id);
  }
  std::vector<CellId> all;
  for (const auto& part : Utilities::MPI::all_gather(comm, initial))
    for (const auto& id : part)
      all.emplace_back(id);
  if (!all.empty())
    convert(all);
}

template <int dim>
void FemParticleCoupling<dim>::prepare() {
  if (method_)
    return;
  const auto& dh = fem_.dof_handler();
  const auto& fe = fem_.fe();
  impl_->owned_cells.clear();
  double h_min = std::numeric_limits<double>::max(), h_max = 0;
  bool have_law = false;
  for (const auto& cell : dh.active_cell_iterators())
    if (cell->is_locally_owned()) {
      impl_->owned_cells.emplace(cell->id().to_string(), cell);
      h_min = std::min(h_min, cell->minimum_vertex_distance());
      h_max = std::max(h_max, cell->diameter() / std::sqrt(double(dim)));
      if (!have_law) {
        const auto& law = fem_.cell_material(cell);
        youngs_ = law.youngs_modulus();
        poisson_ = law.poisson_ratio();
        density_ = law.density();
        have_law = true;
      }
    }
  const MPI_Comm comm = fem_.mpi_communicator();
  h_min = Utilities::MPI::min(h_min, comm);
  // E, ν, ρ from the lowest rank that owns cells.
  const unsigned int rank = Utilities::MPI::this_mpi_process(comm);
  const unsigned int source = Utilities::MPI::min(have_law ? rank : 1u << 30, comm);
  std::vector<double> props{youngs_, poisson_, density_};
  props = Utilities::MPI::broadcast(comm, props, source);
  youngs_ = props[0];
  poisson_ = props[1];
  density_ = props[2];
  // The lattice spacing of the particles (uniform meshes: cell edge / n).
  spacing_ = h_min / prm_.particles_per_direction;
  impl_->owned_by_index.assign(dh.get_triangulation().n_active_cells(), typename Impl::DoFCell());
  for (const auto& [id, cell] : impl_->owned_cells)
    impl_->owned_by_index[cell->active_cell_index()] = cell;
  impl_->lattice_cells.clear();
  for (const auto& cell : impl_->owned_by_index)
    if (cell.state() == IteratorState::valid &&
        cell->minimum_vertex_distance() <= 1.5 * spacing_ * prm_.particles_per_direction)
      impl_->lattice_cells.push_back(cell);

  impl_->shape.reinit(impl_->points.size(), fe.n_dofs_per_cell());
  for (unsigned int q = 0; q < impl_->points.size(); ++q)
    for (unsigned int i = 0; i < fe.n_dofs_per_cell(); ++i)
      impl_->shape(q, i) = fe.shape_value(i, impl_->points.point(q));

  if (!prm_.make_method)
    throw InvalidInput("Coupling", "no particle method was read for the coupling",
                       "Coupling parameters parsed with Effects/Particles method");
  // Calibrated to the law of the FEM cells the particles replace (the same law on every
  // rank; the law object itself is not needed by methods without point-wise laws).
  method_ = prm_.make_method(meshfree::ParticleMaterial{youngs_, poisson_, density_, nullptr});
  if (dim == 2 && method_->thickness() != 1.0)
    throw InvalidInput("Coupling/" +
                           meshfree::ParticleMethods::instance()
                               .get(prm_.particles_method, "Effects/Particles method")
                               .section +
                           "/Thickness",
                       "2-D FEM works per unit thickness",
                       "1 (results are per metre of thickness) [m]");
}

// ---------------------------------------------------------------- totals

template <int dim>
double FemParticleCoupling<dim>::total_mass() const {
  double m = 0;
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i])
      m += particles_.mass(i);
  const auto& lumped = fem_.lumped_mass();
  double mf = 0;
  for (const auto i : lumped.locally_owned_elements())
    mf += lumped(i);
  mf = Utilities::MPI::sum(mf, fem_.mpi_communicator()) / dim; // one mass per component
  return m + mf;
}

template <int dim>
Tensor<1, dim> FemParticleCoupling<dim>::total_momentum() const {
  Tensor<1, dim> p; // owned free particles summed over the ranks, plus the FEM's lumped M v
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i] && is_owned(i))
      p += particles_.mass(i) * particles_.velocity(i);
  for (unsigned int d = 0; d < dim; ++d)
    p[d] = Utilities::MPI::sum(p[d], fem_.mpi_communicator());
  return p + fem_.momentum();
}

template <int dim>
double FemParticleCoupling<dim>::kinetic_energy() const {
  double e = 0;
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i] && is_owned(i))
      e += 0.5 * particles_.mass(i) * particles_.velocity(i).norm_square();
  return Utilities::MPI::sum(e, fem_.mpi_communicator()) + fem_.kinetic_energy();
}

template <int dim>
double FemParticleCoupling<dim>::strain_energy() const {
  // Bonds are stored from free particles only: W = ¼ Σ k e² over the free rows.
  const auto w =
      method_ ? method_->strain_energy_density(particles_, bonds_) : std::vector<double>();
  double e = 0; // rows live with their owners
  for (unsigned int i = 0; i < w.size(); ++i)
    if (free_[i] && is_owned(i))
      e += w[i] * particles_.volume(i);
  return Utilities::MPI::sum(e, fem_.mpi_communicator()) + fem_.strain_energy();
}

// ---------------------------------------------------------------- conversion

template <int dim>
std::vector<CellId> FemParticleCoupling<dim>::flagged_cells() const {
  ScopedTime time(timings_.criteria);
  const bool any = prm_.principal_strain_threshold > 0 || prm_.plastic_strain_threshold > 0 ||
                   prm_.min_jacobian_ratio > 0 || prm_.min_time_step > 0;
  std::vector<Point<dim>> centres;
  if (any) {
    // Only active cells of the particle lattice's size can convert (the refinement box).
    std::vector<bool> candidate(fem_.dof_handler().get_triangulation().n_active_cells(), false);
    for (const auto& cell : impl_->lattice_cells)
      candidate[cell->active_cell_index()] = fem_.is_active(cell);
    fem::CellIndicators<dim> indicators;
    indicators.compute(fem_, prm_.plastic_strain_threshold > 0, candidate,
                       prm_.min_jacobian_ratio > 0 || prm_.min_time_step > 0);
    for (const auto& cell : impl_->lattice_cells) {
      if (!candidate[cell->active_cell_index()])
        continue;
      const unsigned int c = cell->active_cell_index();
      bool flag = false;
      flag |= prm_.principal_strain_threshold > 0 &&
              indicators.max_principal_strain(c) >= prm_.principal_strain_threshold;
      flag |= prm_.plastic_strain_threshold > 0 &&
              indicators.equivalent_plastic_strain(c) >= prm_.plastic_strain_threshold;
      flag |= prm_.min_jacobian_ratio > 0 &&
              indicators.min_jacobian_ratio(c) <= prm_.min_jacobian_ratio;
      flag |= prm_.min_time_step > 0 && indicators.stable_time_step(c) <= prm_.min_time_step;
      if (flag)
        centres.push_back(cell->center());
    }
  }
  const MPI_Comm comm = fem_.mpi_communicator();
  std::vector<Point<dim>> all_centres;
  for (const auto& part : Utilities::MPI::all_gather(comm, centres))
    all_centres.insert(all_centres.end(), part.begin(), part.end());
  std::vector<std::string> mine;
  if (!all_centres.empty()) {
    const double reach = std::max(prm_.buffer, 1e-9 * spacing_);
    PointBins<dim> bins(all_centres, std::max(prm_.buffer, spacing_));
    for (const auto& cell : impl_->lattice_cells)
      if (fem_.is_active(cell) && !bins.within(cell->center(), reach).empty())
        mine.push_back(cell->id().to_string());
  }
  std::vector<CellId> out;
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& id : part)
      out.emplace_back(id);
  return out;
}

template <int dim>
typename FemParticleCoupling<dim>::ConversionReport FemParticleCoupling<dim>::convert_flagged() {
  const auto cells = flagged_cells();
  if (cells.empty())
    return ConversionReport();
  return convert(cells);
}

template <int dim>
typename FemParticleCoupling<dim>::ConversionReport
FemParticleCoupling<dim>::convert(const std::vector<CellId>& cells) {
  ConversionReport report;
  std::set<std::string> todo;
  for (const auto& id : cells) {
    const std::string s = id.to_string();
    if (!converted_.count(s))
      todo.insert(s);
  }
  report.cells = static_cast<unsigned int>(todo.size());
  if (todo.empty())
    return report;
  const MPI_Comm comm = fem_.mpi_communicator();
  {
    ScopedTime time(timings_.totals);
    report.mass_before = total_mass();
    report.momentum_before = total_momentum();
    report.kinetic_before = kinetic_energy();
  }
  std::optional<ScopedTime> records_time(timings_.records);

  // Records of the new free particles from the ranks owning their cells.
  const auto& fe = fem_.fe();
  const auto& bcs = fem_.boundary_conditions().dirichlet();
  FEValues<dim> at_points(fem_.mapping(), fe, impl_->points,
                          update_values | update_quadrature_points | update_JxW_values);
  FEValues<dim> at_gauss(fem_.mapping(), fe, fem_.quadrature(), update_values | update_JxW_values);
  const FEValuesExtractors::Vector disp(0);
  const unsigned int np = impl_->points.size();
  std::vector<Tensor<1, dim>> u(np), v(np), vg(fem_.quadrature().size());
  std::vector<double> temperature(np, 0.0);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  const auto& hanging = fem_.hanging_constraints();
  const auto& velocity = fem_.velocity();
  std::vector<ParticleRecord<dim>> mine;
  for (const auto& id : todo) {
    const auto it = impl_->owned_cells.find(id);
    if (it == impl_->owned_cells.end())
      continue;
    const auto& cell = it->second;
    // PD is calibrated on one lattice spacing: coarser cells would carry a wrong horizon.
    if (cell->minimum_vertex_distance() > 1.5 * spacing_ * prm_.particles_per_direction)
      throw InvalidInput("Coupling/Refinement region lower corner",
                         "a cell of edge " + std::to_string(cell->minimum_vertex_distance()) +
                             " m at (" + std::to_string(cell->center()[0]) + ", " +
                             std::to_string(cell->center()[1]) +
                             ") is to become particles, but the particle lattice is " +
                             std::to_string(spacing_) + " m",
                         "a refinement box (with Region refinements) that covers every cell "
                         "the conversion can reach");
    at_points.reinit(cell);
    at_gauss.reinit(cell);
    at_points[disp].get_function_values(fem_.displacement(), u);
    at_points[disp].get_function_values(fem_.velocity(), v);
    at_gauss[disp].get_function_values(fem_.velocity(), vg);
    if (heat_)
      heat_->temperature_at_unit_points(cell, impl_->points.get_points(), temperature);
    const double rho = fem_.cell_material(cell).density();
    // The mass and momentum this cell takes out of the lumped FEM mass (same quadrature).
    double cell_mass = 0;
    Tensor<1, dim> cell_momentum;
    for (unsigned int q = 0; q < vg.size(); ++q) {
      cell_mass += rho * at_gauss.JxW(q);
      cell_momentum += rho * at_gauss.JxW(q) * vg[q];
    }
    double volume = 0;
    for (unsigned int q = 0; q < np; ++q)
      volume += at_points.JxW(q);
    const double scale = cell_mass / (rho * volume); // 1 up to round-off on parallelograms
    Tensor<1, dim> p_interp;
    for (unsigned int q = 0; q < np; ++q)
      p_interp += rho * at_points.JxW(q) * scale * v[q];
    const Tensor<1, dim> dv = (cell_momentum - p_interp) / cell_mass;
    // Kinetic energy the cell's nodes lose: ½ Σ Δm_a v_a² with Δm_a the cell's share of the
    // row-sum lumped mass (condensed onto the masters of hanging nodes, as the solver does).
    std::map<types::global_dof_index, double> dm;
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i) {
      double m = 0;
      for (unsigned int q = 0; q < vg.size(); ++q)
        m += rho * at_gauss.shape_value(i, q) * at_gauss.JxW(q);
      if (const auto* entries = hanging.get_constraint_entries(dofs[i]))
        for (const auto& [master, weight] : *entries)
          dm[master] += weight * m;
      else
        dm[dofs[i]] += m;
    }
    double nodal_kinetic = 0;
    for (const auto& [dof, m] : dm)
      nodal_kinetic += 0.5 * m * velocity(dof) * velocity(dof);
    // The particle velocities are the cell's mean velocity plus the interpolated fluctuation
    // about it, scaled by λ so that they carry that kinetic energy as well as the momentum:
    // ½ M |v̄|² + λ² ½ Σ m_p |w_p|² = nodal. The nodal energy is at least ½ M |v̄|² (Jensen),
    // so λ is real; λ → 1 as the field is resolved, and it is reported. One particle per cell
    // (no fluctuation) keeps λ = 1 and the defect is logged.
    const Tensor<1, dim> mean = cell_momentum / cell_mass;
    double fluctuation = 0;
    for (unsigned int q = 0; q < np; ++q)
      fluctuation += 0.5 * rho * at_points.JxW(q) * scale * (v[q] + dv - mean).norm_square();
    const double excess = nodal_kinetic - 0.5 * cell_mass * mean.norm_square();
    double lambda = 1;
    if (prm_.conserve_kinetic_energy && fluctuation > 1e-14 * nodal_kinetic && excess > 0)
      lambda = std::sqrt(excess / fluctuation);
    report.max_velocity_scale = std::max(report.max_velocity_scale, lambda);
    std::uint32_t slots = 0;
    for (unsigned int k = 0; k < bcs.size(); ++k)
      for (const unsigned int f : cell->face_indices())
        if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == bcs[k].boundary_id)
          slots |= 1u << k;
    for (unsigned int q = 0; q < np; ++q) {
      ParticleRecord<dim> r;
      r.cell = id;
      r.point = q;
      r.free = true;
      r.fixed_slots = slots;
      r.volume = at_points.JxW(q) * scale;
      r.density = rho;
      r.temperature = temperature[q];
      r.position = at_points.quadrature_point(q);
      r.displacement = u[q];
      for (unsigned int d = 0; d < dim; ++d)
        r.velocity[d] = mean[d] + lambda * (v[q][d] + dv[d] - mean[d]);
      mine.push_back(std::move(r));
    }
  }
  unsigned int added = 0;
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& r : part) {
      unsigned int i;
      const auto existing = index_of_.find({r.cell, r.point});
      if (existing != index_of_.end()) {
        i = existing->second;
      } else {
        i = particles_.add_particle(r.position, r.volume);
        index_of_[{r.cell, r.point}] = i;
        free_.push_back(0);
        add_host(r.cell, r.point);
        impl_->fixed_slots.push_back(0);
      }
      free_[i] = 1;
      impl_->fixed_slots[i] = r.fixed_slots;
      particles_.volume(i) = r.volume;
      particles_.density(i) = r.density;
      particles_.temperature(i) = r.temperature;
      particles_.displacement(i) = r.displacement;
      particles_.velocity(i) = r.velocity;
      ++added;
    }
  report.particles = added;
  const unsigned int batch = static_cast<unsigned int>(reports_.size());
  for (const auto& id : todo)
    converted_.emplace(id, batch);

  records_time.reset();
  // Deactivate the converted cells (owned and ghost cells, by CellId).
  std::optional<ScopedTime> deactivation_time(timings_.deactivation);
  // The cells converted before are inactive already; of the others only this batch turns.
  std::set<CellId> batch_ids;
  for (const auto& id : todo)
    batch_ids.emplace(id);
  std::vector<bool> active(fem_.dof_handler().get_triangulation().n_active_cells(), true);
  for (const auto& cell : fem_.dof_handler().active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) &&
        (!fem_.is_active(cell) || batch_ids.count(cell->id())))
      active[cell->active_cell_index()] = false;
  fem_.set_active_cells(active);
  deactivation_time.reset();
  rebuild_interface();

  ScopedTime time(timings_.totals);
  report.max_velocity_scale =
      Utilities::MPI::max(report.max_velocity_scale, fem_.mpi_communicator());
  report.mass_after = total_mass();
  report.momentum_after = total_momentum();
  report.kinetic_after = kinetic_energy();
  reports_.push_back(report);
  return report;
}

// ---------------------------------------------------------------- interface

template <int dim>
void FemParticleCoupling<dim>::rebuild_interface() {
  const MPI_Comm comm = fem_.mpi_communicator();
  const auto& fe = fem_.fe();
  const unsigned int np = impl_->points.size();

  // 1. Ghost particles: every point of an active cell near a free particle (whole cells).
  std::optional<ScopedTime> ghosts_time(timings_.ghosts);
  // Only particles freed since the last search can need new ghosts: every active cell within
  // reach of an earlier free particle hosts ghosts already (cells never turn active again).
  std::vector<Point<dim>> free_points, new_free_points;
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i]) {
      free_points.push_back(particles_.reference_position(i));
      if (i >= impl_->free_searched.size() || !impl_->free_searched[i])
        new_free_points.push_back(particles_.reference_position(i));
    }
  // Bonds reach δ + h/2 (partial volumes), so a ghost bonded to a free particle needs ghosts
  // out to 2(δ + h/2) for a complete horizon of its own.
  const double reach = prm_.ghost_layer * (horizon() + 0.5 * spacing_) + 0.5 * spacing_;
  PointBins<dim> free_bins(new_free_points, reach);
  std::vector<ParticleRecord<dim>> mine;
  std::vector<Point<dim>> xs(np);
  FEValues<dim> at_points(fem_.mapping(), fe, impl_->points, update_JxW_values);
  std::vector<std::uint8_t> hosts(impl_->owned_by_index.size(), 0); // owned cells with particles
  for (const int c : impl_->host_index)
    if (c >= 0)
      hosts[c] = 1;
  for (const auto& [id, cell] : impl_->owned_cells) {
    if (new_free_points.empty())
      break;
    // Cells hosting particles already, or farther than the reach from every free particle
    // (tested at the centre with the half diagonal added), need no mapping of their points.
    if (!fem_.is_active(cell) || hosts[cell->active_cell_index()] ||
        !free_bins.any_within(cell->center(), reach + 0.5 * cell->diameter()))
      continue;
    bool near = false;
    for (unsigned int q = 0; q < np; ++q) {
      xs[q] = fem_.mapping().transform_unit_to_real_cell(cell, impl_->points.point(q));
      near = near || free_bins.any_within(xs[q], reach);
    }
    if (!near)
      continue;
    at_points.reinit(cell);
    const double rho = fem_.cell_material(cell).density();
    for (unsigned int q = 0; q < np; ++q) {
      ParticleRecord<dim> r; // a ghost: state from the FEM once the layer is built
      r.cell = id;
      r.point = q;
      r.volume = at_points.JxW(q);
      r.density = rho;
      r.position = xs[q];
      mine.push_back(std::move(r));
    }
  }
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& r : part) {
      const unsigned int i = particles_.add_particle(r.position, r.volume);
      particles_.density(i) = r.density;
      index_of_[{r.cell, r.point}] = i;
      free_.push_back(0);
      add_host(r.cell, r.point);
      impl_->fixed_slots.push_back(0);
    }

  impl_->free_searched.assign(free_.begin(), free_.end());

  // 2. Local host-cell tables for ghosts (displacements) and free particles (temperatures).
  impl_->ghost_cells.clear();
  impl_->free_cells.clear();
  {
    // Rows by owned host cell, in ascending active cell index. A cell's points are all free
    // (converted cell) or all ghosts (active cell): each row goes to one table.
    std::vector<int> slot(impl_->owned_by_index.size(), -1);
    std::vector<std::pair<int, std::vector<int>>> rows; // (active cell index, row)
    for (unsigned int i = 0; i < particles_.size(); ++i) {
      const int c = impl_->host_index[i];
      if (c < 0)
        continue;
      if (slot[c] < 0) {
        slot[c] = static_cast<int>(rows.size());
        rows.emplace_back(c, std::vector<int>(np, -1));
      }
      rows[slot[c]].second[host_point_[i]] = static_cast<int>(i);
    }
    std::sort(rows.begin(), rows.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [c, row] : rows) {
      const int any = *std::max_element(row.begin(), row.end());
      auto& table = free_[any] ? impl_->free_cells : impl_->ghost_cells;
      table.emplace_back(impl_->owned_by_index[c], std::move(row));
    }
  }
  {
    // Local indices in the ghosted FEM vectors: element access without a map lookup per read.
    const auto& map = fem_.displacement().trilinos_vector().Map();
    std::vector<types::global_dof_index> dofs(fem_.fe().n_dofs_per_cell());
    impl_->ghost_lids.clear();
    for (const auto& [cell, row] : impl_->ghost_cells) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs) {
        const int lid = map.LID(static_cast<TrilinosWrappers::types::int_type>(d));
        Assert(lid >= 0, ExcInternalError());
        impl_->ghost_lids.push_back(lid);
      }
    }
  }

  // 3. Dirichlet conditions of converted boundary cells act on their particles.
  impl_->fixed.clear();
  const auto& bcs = fem_.boundary_conditions().dirichlet();
  for (unsigned int i = 0; i < particles_.size(); ++i) {
    particles_.set_fixed(i, false);
    if (!free_[i])
      continue;
    for (unsigned int k = 0; k < bcs.size(); ++k)
      if ((impl_->fixed_slots[i] >> k) & 1u) {
        impl_->fixed.push_back({i, k});
        for (unsigned int c = 0; c < dim; ++c)
          if (bcs[k].mask[c])
            particles_.set_fixed(i, c, true);
      }
  }

  ghosts_time.reset();
  {
    ScopedTime time(timings_.bonds);
    rebuild_bonds();
  }

  // 4. Interface DoFs: shared by an active and a converted cell; MLS fit of free particles.
  ScopedTime interface_time(timings_.interface);
  impl_->interface.clear();
  impl_->interface_registered = false;
  const auto& dh = fem_.dof_handler();
  // DoFs of active cells (flags by index among the locally relevant DoFs), then the DoFs of
  // converted cells among them, with their support points.
  IndexSet relevant;
  DoFTools::extract_locally_relevant_dofs(dh, relevant);
  std::vector<std::uint8_t> on_active(relevant.n_elements(), 0);
  std::map<types::global_dof_index, std::pair<Point<dim>, unsigned int>> where;
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  const auto& unit_support = fe.get_unit_support_points();
  for (const auto& cell : dh.active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) && fem_.is_active(cell)) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs)
        on_active[relevant.index_within_set(d)] = 1;
    }
  for (const auto& cell : dh.active_cell_iterators()) {
    if (!(cell->is_locally_owned() || cell->is_ghost()) || fem_.is_active(cell))
      continue;
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i)
      if (on_active[relevant.index_within_set(dofs[i])] && !where.count(dofs[i]))
        where[dofs[i]] = {fem_.mapping().transform_unit_to_real_cell(cell, unit_support[i]),
                          fe.system_to_component_index(i).first};
  }
  PointBins<dim> bins(free_points, prm_.interface_radius * spacing_ * 4);
  std::vector<unsigned int> free_index;
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i])
      free_index.push_back(i);
  for (const auto& [dof, pc] : where) {
    const Point<dim>& X = pc.first;
    typename Impl::InterfaceDof entry{dof, pc.second, {}};
    bool ok = false;
    for (unsigned int attempt = 0; attempt < 3 && !ok; ++attempt) {
      const double r = prm_.interface_radius * spacing_ * (1.0 + 0.5 * attempt);
      const auto weights = mls_linear_weights<dim>(X, free_points, bins.within(X, r), r, spacing_);
      if (!weights)
        continue;
      entry.weights.clear();
      for (const auto& [k, phi] : *weights)
        entry.weights.emplace_back(free_index[k], phi);
      ok = true;
    }
    if (!ok)
      throw NumericalFailure(
          "singular moving-least-squares fit for an interface node",
          "FEM node at (" +
              [&] {
                std::ostringstream s;
                s << X;
                return s.str();
              }() +
              ")",
          "convert larger blocks (Coupling/Buffer), use more particles per "
          "cell direction or a larger Coupling/Interface radius");
    impl_->interface.push_back(std::move(entry));
  }
  plan_exchange();
  update_ghosts(); // owned ghosts from the FEM, then the halo (free particles included)
  update_interface_dofs();
}

template <int dim>
void FemParticleCoupling<dim>::plan_exchange() {
  const MPI_Comm comm = fem_.mpi_communicator();
  impl_->halo_recv.clear();
  impl_->halo_send.clear();
  if (Utilities::MPI::n_mpi_processes(comm) == 1) {
    owner_.clear(); // everything is owned
    return;
  }
  std::vector<int> owner(particles_.size(), -1);
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (impl_->host_index[i] >= 0)
      owner[i] = static_cast<int>(rank_);
  owner_.resize(owner.size());
  MPI_Allreduce(owner.data(), owner_.data(), static_cast<int>(owner.size()), MPI_INT, MPI_MAX,
                comm);
  // Read here, owned elsewhere: bond partners of the owned rows and the MLS stencils of this
  // rank's interface nodes.
  std::set<unsigned int> needed;
  for (unsigned int i = 0; i < bonds_.n_particles(); ++i)
    for (std::size_t k = bonds_.begin(i); k < bonds_.end(i); ++k)
      if (!is_owned(bonds_.neighbor[k]))
        needed.insert(bonds_.neighbor[k]);
  for (const auto& entry : impl_->interface)
    for (const auto& [p, w] : entry.weights)
      if (!is_owned(p))
        needed.insert(p);
  std::map<unsigned int, std::vector<unsigned int>> requests;
  for (const unsigned int j : needed) {
    AssertThrow(owner_[j] >= 0, ExcMessage("particle " + std::to_string(j) + " has no owner"));
    requests[static_cast<unsigned int>(owner_[j])].push_back(j);
  }
  impl_->halo_recv = requests;
  impl_->halo_send = Utilities::MPI::some_to_some(comm, requests);
}

template <int dim>
void FemParticleCoupling<dim>::exchange_halo() {
  const MPI_Comm comm = fem_.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr int tag = 7301;
  constexpr unsigned int width = 2 * dim; // u, v
  std::vector<std::vector<double>> out, in;
  std::vector<MPI_Request> requests;
  for (const auto& [rank, list] : impl_->halo_send) {
    out.emplace_back();
    auto& b = out.back();
    b.reserve(width * list.size());
    for (const unsigned int i : list)
      for (unsigned int d = 0; d < dim; ++d)
        b.push_back(particles_.displacement(i)[d]);
    for (const unsigned int i : list)
      for (unsigned int d = 0; d < dim; ++d)
        b.push_back(particles_.velocity(i)[d]);
  }
  requests.reserve(impl_->halo_send.size() + impl_->halo_recv.size());
  for (const auto& [rank, list] : impl_->halo_recv) {
    in.emplace_back(width * list.size());
    requests.emplace_back();
    MPI_Irecv(in.back().data(), static_cast<int>(in.back().size()), MPI_DOUBLE,
              static_cast<int>(rank), tag, comm, &requests.back());
  }
  std::size_t k = 0;
  for (const auto& [rank, list] : impl_->halo_send) {
    requests.emplace_back();
    MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_DOUBLE, static_cast<int>(rank),
              tag, comm, &requests.back());
    ++k;
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  k = 0;
  for (const auto& [rank, list] : impl_->halo_recv) {
    const auto& b = in[k++];
    const std::size_t n = list.size();
    for (std::size_t m = 0; m < n; ++m)
      for (unsigned int d = 0; d < dim; ++d) {
        particles_.displacement(list[m])[d] = b[dim * m + d];
        particles_.velocity(list[m])[d] = b[dim * n + dim * m + d];
      }
  }
}

template <int dim>
void FemParticleCoupling<dim>::synchronise() const {
  auto& p = const_cast<meshfree::ParticleSet<dim>&>(particles_);
  if (method_ && n_free_particles() > 0)
    method_->update_damage(p, bonds_); // owned rows
  const MPI_Comm comm = fem_.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr unsigned int width = 2 * dim + 2; // u, v, damage, temperature
  std::vector<double> buffer(width * particles_.size(), 0.0);
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (is_owned(i)) {
      double* b = &buffer[width * i];
      for (unsigned int d = 0; d < dim; ++d) {
        b[d] = particles_.displacement(i)[d];
        b[dim + d] = particles_.velocity(i)[d];
      }
      b[2 * dim] = particles_.damage(i);
      b[2 * dim + 1] = particles_.temperature(i);
    }
  Utilities::MPI::sum(buffer, comm, buffer);
  for (unsigned int i = 0; i < particles_.size(); ++i) {
    const double* b = &buffer[width * i];
    for (unsigned int d = 0; d < dim; ++d) {
      p.displacement(i)[d] = b[d];
      p.velocity(i)[d] = b[dim + d];
    }
    p.damage(i) = b[2 * dim];
    p.temperature(i) = b[2 * dim + 1];
  }
}

template <int dim>
void FemParticleCoupling<dim>::add_host(const std::string& cell_id, unsigned int point) {
  host_cell_.push_back(cell_id);
  host_point_.push_back(point);
  const auto it = impl_->owned_cells.find(cell_id);
  impl_->host_index.push_back(
      it == impl_->owned_cells.end() ? -1 : static_cast<int>(it->second->active_cell_index()));
}

template <int dim>
void FemParticleCoupling<dim>::rebuild_bonds() {
  // Broken pairs survive a rebuild (particle indices never change). Sorted pairs (i < j).
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  for (unsigned int i = 0; i < bonds_.n_particles(); ++i)
    for (std::size_t k = bonds_.begin(i); k < bonds_.end(i); ++k)
      if (bonds_.broken[k])
        broken.emplace_back(std::min(i, bonds_.neighbor[k]), std::max(i, bonds_.neighbor[k]));
  if (Utilities::MPI::n_mpi_processes(fem_.mpi_communicator()) > 1) {
    // Rows live with their owners: every rank learns every broken pair (a particle that turns
    // from ghost to free inherits the breaks its partners recorded).
    const auto mine = broken;
    broken.clear();
    for (const auto& part : Utilities::MPI::all_gather(fem_.mpi_communicator(), mine))
      broken.insert(broken.end(), part.begin(), part.end());
  }
  std::sort(broken.begin(), broken.end());
  broken.erase(std::unique(broken.begin(), broken.end()), broken.end());
  std::vector<std::uint8_t> in_broken(particles_.size(), 0); // the search only where it can hit
  for (const auto& [i, j] : broken)
    in_broken[i] = in_broken[j] = 1;
  const auto was_broken = [&](unsigned int i, unsigned int j) {
    return in_broken[i] && in_broken[j] &&
           std::binary_search(broken.begin(), broken.end(),
                              std::make_pair(std::min(i, j), std::max(i, j)));
  };

  auto options = method_->neighbor_options(spacing_);
  for (const auto& c : prm_.cracks) {
    if constexpr (dim == 2)
      options.pre_cracks.push_back(
          meshfree::PreCrack<dim>::segment(Point<dim>(c[0], c[1]), Point<dim>(c[2], c[3])));
    else
      options.pre_cracks.push_back(meshfree::PreCrack<dim>::quadrilateral(
          Point<dim>(c[0], c[1], c[2]), Point<dim>(c[3], c[4], c[5]), Point<dim>(c[6], c[7], c[8]),
          Point<dim>(c[9], c[10], c[11])));
  }
  // Particles are only appended and never move; a conversion changes the volumes of the ghosts
  // it frees. The search reuses the rows that neither touches (the same list as a full build).
  meshfree::NeighborSearch<dim> search(options);
  auto& all = impl_->searched_bonds;
  if (all.n_particles() == 0) {
    all = search.build(particles_);
  } else {
    std::vector<unsigned int> changed;
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (particles_.volume(i) != impl_->searched_volumes[i])
        changed.push_back(i);
    all = search.extend(particles_, all, changed);
  }
  impl_->searched_volumes = particles_.volumes();

  // Owners (before the first plan: host cells owned here) and their rows.
  std::vector<std::uint8_t> mine(particles_.size(), 1);
  if (Utilities::MPI::n_mpi_processes(fem_.mpi_communicator()) > 1)
    for (unsigned int i = 0; i < particles_.size(); ++i)
      mine[i] = impl_->host_index[i] >= 0 ? 1 : 0;
  // Keep the rows of the free particles this rank owns: ghosts are driven and need no force,
  // other ranks' particles are theirs to move.
  meshfree::BondList<dim> kept;
  kept.horizon = all.horizon;
  kept.offsets.assign(all.n_particles() + 1, 0);
  const bool has_volume = !all.volume_fraction.empty(), has_surface = !all.surface_factor.empty();
  {
    std::size_t n_kept = 0;
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (free_[i] && mine[i])
        n_kept += all.end(i) - all.begin(i);
    for (auto* v : {&kept.length, &kept.influence})
      v->reserve(n_kept);
    kept.neighbor.reserve(n_kept);
    kept.xi.reserve(n_kept);
    kept.broken.reserve(n_kept);
    if (has_volume)
      kept.volume_fraction.reserve(n_kept);
    if (has_surface)
      kept.surface_factor.reserve(n_kept);
  }
  for (unsigned int i = 0; i < all.n_particles(); ++i) {
    if (free_[i] && mine[i])
      for (std::size_t k = all.begin(i); k < all.end(i); ++k) {
        const unsigned int j = all.neighbor[k];
        kept.neighbor.push_back(j);
        kept.xi.push_back(all.xi[k]);
        kept.length.push_back(all.length[k]);
        kept.influence.push_back(all.influence[k]);
        kept.broken.push_back(all.broken[k] || was_broken(i, j));
        if (has_volume)
          kept.volume_fraction.push_back(all.volume_fraction[k]);
        if (has_surface)
          kept.surface_factor.push_back(all.surface_factor[k]);
      }
    kept.offsets[i + 1] = kept.neighbor.size();
  }
  bonds_ = std::move(kept);
  method_->initialise(particles_, bonds_);
}

template <int dim>
void FemParticleCoupling<dim>::update_ghosts() {
  // u and v of the ghosts this rank owns (host cell owned here) = FEM interpolation; then the
  // halo brings the particles owned elsewhere that this rank reads.
  const auto& fe = fem_.fe();
  const unsigned int n = fe.n_dofs_per_cell();
  const double* uu = fem_.displacement().trilinos_vector()[0];
  const double* vv = fem_.velocity().trilinos_vector()[0];
  std::vector<unsigned int> component(n);
  for (unsigned int i = 0; i < n; ++i)
    component[i] = fe.system_to_component_index(i).first;
  const long n_cells = static_cast<long>(impl_->ghost_cells.size());
  // Each ghost is written by its own host cell only.
#pragma omp parallel for schedule(static) if (n_cells > 1000)
  for (long k = 0; k < n_cells; ++k) {
    const auto& row = impl_->ghost_cells[k].second;
    const int* lids = &impl_->ghost_lids[k * n];
    for (unsigned int q = 0; q < row.size(); ++q) {
      if (row[q] < 0)
        continue;
      double b[2 * dim] = {};
      for (unsigned int i = 0; i < n; ++i) {
        b[component[i]] += impl_->shape(q, i) * uu[lids[i]];
        b[dim + component[i]] += impl_->shape(q, i) * vv[lids[i]];
      }
      for (unsigned int d = 0; d < dim; ++d) {
        particles_.displacement(row[q])[d] = b[d];
        particles_.velocity(row[q])[d] = b[dim + d];
      }
    }
  }
  exchange_halo();
}

template <int dim>
void FemParticleCoupling<dim>::update_interface_dofs() {
  // Entries are in ascending DoF order (built from an ordered map), the key order of the
  // solver's driven set: after the set is registered once, a step only passes values.
  auto& values = impl_->interface_values;
  values.resize(impl_->interface.size());
  for (std::size_t k = 0; k < impl_->interface.size(); ++k) {
    const auto& entry = impl_->interface[k];
    double value = 0;
    for (const auto& [p, w] : entry.weights)
      value += w * particles_.displacement(p)[entry.component];
    values[k] = value;
  }
  if (impl_->interface_registered) {
    fem_.set_driven_values(values);
    return;
  }
  std::map<types::global_dof_index, double> driven;
  for (std::size_t k = 0; k < impl_->interface.size(); ++k)
    driven.emplace_hint(driven.end(), impl_->interface[k].dof, values[k]);
  fem_.set_driven_dofs(driven);
  impl_->interface_registered = true;
}

template <int dim>
void FemParticleCoupling<dim>::apply_particle_dirichlet(double time, double dt) {
  const auto& bcs = fem_.boundary_conditions().dirichlet();
  Vector<double> value(dim);
  for (const auto& f : impl_->fixed) {
    if (!is_owned(f.particle))
      continue;
    const auto& bc = bcs[f.slot];
    bc.function->set_time(time);
    bc.function->vector_value(particles_.reference_position(f.particle), value);
    for (unsigned int c = 0; c < dim; ++c)
      if (bc.mask[c]) {
        auto& u = particles_.displacement(f.particle)[c];
        particles_.velocity(f.particle)[c] = dt > 0 ? (value[c] - u) / dt : 0.0;
        u = value[c];
      }
  }
}

// ---------------------------------------------------------------- time stepping

template <int dim>
void FemParticleCoupling<dim>::refresh() {
  update_ghosts();
  update_interface_dofs();
}

template <int dim>
double FemParticleCoupling<dim>::stable_time_step() const {
  double dt = fem_.stable_time_step();
  if (n_free_particles() > 0) {
    const auto S = method_->stiffness_bound(particles_, bonds_);
    for (unsigned int i = 0; i < particles_.size(); ++i)
      if (free_[i] && S[i] > 0)
        dt = std::min(dt, prm_.time_step_safety * std::sqrt(2.0 * particles_.density(i) / S[i]));
  }
  return Utilities::MPI::min(dt, fem_.mpi_communicator()); // rows live with their owners
}

template <int dim>
void FemParticleCoupling<dim>::step(double dt) {
  advance(dt, fem_.parameters().mass_damping, time_ + dt, false, nullptr);
  time_ += dt;
}

template <int dim>
void FemParticleCoupling<dim>::advance(double dt, double a, double load_time, bool first,
                                       RelaxationSums* sums) {
  // Central differences on both sides, all forces from the state at t_n:
  // 1. PD forces on free particles (ghosts hold the FEM field of t_n); particles to t_{n+1}.
  // 2. Interface DoFs of t_{n+1} from the particles; FEM step from t_n to t_{n+1}.
  // 3. Ghosts to the FEM field of t_{n+1}.
  // A relaxation step (sums given) holds the loads at load_time and adds this rank's sums of
  // the free particles to the FEM's.
  if (n_free_particles() > 0) {
    // With heat, bonds breaking in this force pass release their energy (at the state of t_n)
    // into their particle's heat account: compare with the flags before the pass.
    const bool track_heat = heat_ && prm_.damage && prm_.fracture_heat_fraction > 0;
    if (track_heat)
      impl_->broken_before = bonds_.broken;
    const std::size_t newly_broken = method_->compute_forces(particles_, bonds_, prm_.damage);
    if (track_heat && newly_broken > 0) {
      if (fracture_energy_.size() != particles_.size())
        fracture_energy_.resize(particles_.size(), 0.0);
      for (unsigned int i = 0; i < particles_.size(); ++i)
        for (std::size_t k = bonds_.begin(i); k < bonds_.end(i); ++k)
          if (bonds_.broken[k] && !impl_->broken_before[k]) {
            const double e = method_->bond_energy(particles_, bonds_, i, k);
            fracture_energy_[i] += e;
            fracture_dissipation_ += e;
          }
    }
    auto& previous = impl_->relax_acceleration;
    if (sums && (first || previous.size() != dim * particles_.size()))
      previous.assign(dim * particles_.size(), std::numeric_limits<double>::quiet_NaN());
    // The damped central-difference update of one component, in both loops below.
    const double keep = 1.0 - 0.5 * a * dt, denominator = 1.0 + 0.5 * a * dt;
    const auto advance_component = [&](unsigned int i, unsigned int d, double acc) {
      double& vi = particles_.velocity(i)[d];
      vi = (keep * vi + dt * acc) / denominator;
      particles_.displacement(i)[d] += dt * vi;
    };
    if (!sums) {
      // Independent particles: the threads share them (the relaxation sums below keep one
      // thread and a fixed order).
      const long n = static_cast<long>(particles_.size());
      // A few flops a particle: worth a parallel region from a couple of thousand on.
#pragma omp parallel for schedule(static) if (n > 2000)
      for (long ii = 0; ii < n; ++ii) {
        const unsigned int i = static_cast<unsigned int>(ii);
        if (!free_[i] || !is_owned(i))
          continue;
        const double m = particles_.mass(i);
        for (unsigned int d = 0; d < dim; ++d) {
          if (particles_.is_fixed(i, d))
            continue;
          advance_component(i, d, (particles_.force(i)[d] + particles_.external_force(i)[d]) / m);
        }
      }
    }
    for (unsigned int i = 0; sums && i < particles_.size(); ++i) {
      if (!free_[i] || !is_owned(i))
        continue;
      const double m = particles_.mass(i);
      for (unsigned int d = 0; d < dim; ++d) {
        const double f = particles_.force(i)[d] + particles_.external_force(i)[d];
        if (particles_.is_fixed(i, d)) {
          sums->reaction_square += f * f;
          continue;
        }
        const double acc = f / m;
        sums->add_free(f, acc, previous[dim * i + d], particles_.displacement(i)[d],
                       particles_.velocity(i)[d], dt);
        advance_component(i, d, acc);
      }
    }
    apply_particle_dirichlet(load_time, dt);
    exchange_halo(); // partners and interface stencils at t_{n+1}
    update_interface_dofs();
  }
  if (sums) {
    *sums += fem_.relaxation_step(dt, a, load_time, first);
  } else {
    fem_.explicit_step(dt);
  }
  if (n_ghost_particles() > 0)
    update_ghosts();
  if (heat_ && n_free_particles() > 0) {
    // The FEM temperature drives the temperatures of the free particles owned here (their
    // host cells are this rank's; synchronise() spreads them).
    std::vector<double> values;
    for (const auto& [cell, row] : impl_->free_cells) {
      heat_->temperature_at_unit_points(cell, impl_->points.get_points(), values);
      for (unsigned int q = 0; q < row.size(); ++q)
        if (row[q] >= 0)
          particles_.temperature(row[q]) = values[q];
    }
  }
}

template <int dim>
typename FemParticleCoupling<dim>::RelaxationReport
FemParticleCoupling<dim>::relax(double time, bool with_conversion) {
  // Adaptive dynamic relaxation of the coupled system at the load of `time` (Underwood 1983;
  // Kilic & Madenci 2010 for PD): central differences in pseudo-time with the real lumped and
  // particle masses at the common stable step, and the damping c = 2 sqrt(uᵀ k u / uᵀ u) from
  // the local stiffness estimates of both models (critical for the lowest mode, updated every
  // step, one step late). Converged when ‖free residual‖ ≤ tolerance × max(‖reactions‖,
  // largest ‖free residual‖ of this relaxation). Bonds break as the state relaxes; cells
  // convert at equilibrium, and the state relaxes again after a conversion. Velocities are
  // pseudo-velocities and end at zero.
  const MPI_Comm comm = fem_.mpi_communicator();
  RelaxationReport report;
  double dt = stable_time_step();
  double c = 0, peak_residual = 0;
  bool first = true;
  time_ = time; // held: advance() with sums does not move the clock
  for (unsigned int it = 1; it <= prm_.relaxation_max_iterations; ++it) {
    RelaxationSums local;
    advance(dt, c, time, first, &local);
    first = false;
    double values[4] = {local.stiffness_numerator, local.stiffness_denominator,
                        local.residual_square, local.reaction_square};
    Utilities::MPI::sum(ArrayView<const double>(values, 4), comm, ArrayView<double>(values, 4));
    const double residual = std::sqrt(values[2]), reaction = std::sqrt(values[3]);
    peak_residual = std::max(peak_residual, residual);
    const double scale = std::max(reaction, peak_residual);
    report.iterations = it;
    report.relative_residual = scale > 0 ? residual / scale : 0.0;
    if (!std::isfinite(residual))
      throw NumericalFailure("non-finite residual",
                             "relaxation at t = " + std::to_string(time) + ", iteration " +
                                 std::to_string(it),
                             "check the materials and the loads of this step");
    // The first step's forces are those of the previous state: judge from the second on.
    if (it > 1 && residual <= prm_.relaxation_tolerance * scale) {
      // Conversion is decided at equilibrium, not on the transient strains of the relaxation
      // (which depend on its path and tolerance): cells flagged now convert and the state
      // relaxes again, until no cell converts.
      const auto r = with_conversion ? convert_flagged() : ConversionReport();
      if (r.cells == 0) {
        report.converged = true;
        break;
      }
      report.conversions.push_back(r);
      dt = stable_time_step();
      first = true; // new unknowns: restart the stiffness estimate
      c = 0;
      continue;
    }
    const double q = values[1] > 0 ? values[0] / values[1] : 0.0;
    c = q > 0 ? std::min(2.0 * std::sqrt(q), 2.0 / dt) : 0.0; // c dt ≤ 2 keeps 1 − c dt/2 ≥ 0
    report.damping = c;
  }
  // Quasi-static: the pseudo-velocities go.
  for (unsigned int i = 0; i < particles_.size(); ++i)
    particles_.velocity(i) = Tensor<1, dim>();
  fem_.clear_velocity();
  if (n_ghost_particles() > 0)
    update_ghosts();
  return report;
}

template <int dim>
double FemParticleCoupling<dim>::fracture_dissipation() const {
  return Utilities::MPI::sum(fracture_dissipation_, fem_.mpi_communicator());
}

template <int dim>
Vector<double> FemParticleCoupling<dim>::take_fracture_heat(double elapsed) {
  // Particles are replicated: every rank holds every account, and fills its own host cells.
  Vector<double> power(fem_.dof_handler().get_triangulation().n_active_cells());
  if (fracture_energy_.empty() || !(elapsed > 0))
    return power;
  const double fraction = prm_.fracture_heat_fraction;
  double local = 0; // energy handed over by this rank's host cells [J]
  for (const auto& [cell, row] : impl_->free_cells) {
    double energy = 0;
    for (const int i : row)
      if (i >= 0 && static_cast<unsigned int>(i) < fracture_energy_.size())
        energy += fracture_energy_[i];
    power(cell->active_cell_index()) = fraction * energy / (cell->measure() * elapsed);
    local += energy;
  }
  fracture_heat_ += fraction * Utilities::MPI::sum(local, fem_.mpi_communicator());
  std::fill(fracture_energy_.begin(), fracture_energy_.end(), 0.0);
  return power;
}

// ---------------------------------------------------------------- patch test support

template <int dim>
void FemParticleCoupling<dim>::impose_affine(const Tensor<2, dim>& H) {
  class Affine : public Function<dim> {
   public:
    explicit Affine(const Tensor<2, dim>& H) : Function<dim>(dim), H_(H) {}
    double value(const Point<dim>& x, unsigned int c) const override { return (H_ * x)[c]; }

   private:
    Tensor<2, dim> H_;
  };
  typename fem::MechanicsSolver<dim>::VectorType u(fem_.lumped_mass()), v(fem_.lumped_mass());
  v = 0;
  VectorTools::interpolate(fem_.mapping(), fem_.dof_handler(), Affine(H), u);
  fem_.set_state(u, v);
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i]) {
      particles_.displacement(i) = H * particles_.reference_position(i);
      particles_.velocity(i) = Tensor<1, dim>();
    }
  update_ghosts();
  update_interface_dofs();
  // Driven DoFs take their values in the FEM vector too.
  u = fem_.displacement();
  for (const auto& entry : impl_->interface)
    if (u.locally_owned_elements().is_element(entry.dof)) {
      double value = 0;
      for (const auto& [p, w] : entry.weights)
        value += w * particles_.displacement(p)[entry.component];
      u(entry.dof) = value;
    }
  u.compress(VectorOperation::insert);
  fem_.set_state(u, v);
  update_ghosts();
}

template <int dim>
std::pair<double, double> FemParticleCoupling<dim>::max_free_forces() {
  double fp = 0;
  if (n_free_particles() > 0) {
    method_->compute_forces(particles_, bonds_, false);
    for (unsigned int i = 0; i < particles_.size(); ++i)
      if (free_[i] && is_owned(i))
        for (unsigned int d = 0; d < dim; ++d)
          if (!particles_.is_fixed(i, d))
            fp = std::max(fp, std::abs(particles_.force(i)[d]));
  }
  fp = Utilities::MPI::max(fp, fem_.mpi_communicator());
  const auto& r = fem_.evaluate_residual();
  // Free FEM DoFs: neither on a Dirichlet boundary, nor driven, nor orphaned (zero mass).
  std::set<types::global_dof_index> excluded;
  for (const auto& d : fem_.boundary_conditions().dirichlet()) {
    const IndexSet s = DoFTools::extract_boundary_dofs(fem_.dof_handler(), d.mask, {d.boundary_id});
    for (const auto i : s)
      excluded.insert(i);
  }
  for (const auto& e : impl_->interface)
    excluded.insert(e.dof);
  double ff = 0;
  for (const auto i : r.locally_owned_elements())
    if (!excluded.count(i) && fem_.lumped_mass()(i) > 0)
      ff = std::max(ff, std::abs(r(i)));
  return {fp, Utilities::MPI::max(ff, fem_.mpi_communicator())};
}

// ---------------------------------------------------------------- results

template <int dim>
unsigned int FemParticleCoupling<dim>::n_free_particles() const {
  return static_cast<unsigned int>(std::count(free_.begin(), free_.end(), 1));
}

template <int dim>
unsigned int FemParticleCoupling<dim>::n_ghost_particles() const {
  return static_cast<unsigned int>(free_.size()) - n_free_particles();
}

template <int dim>
std::size_t FemParticleCoupling<dim>::n_broken_bonds() const {
  return Utilities::MPI::sum(bonds_.n_broken(), fem_.mpi_communicator());
}

template <int dim>
double FemParticleCoupling<dim>::max_damage() const {
  if (!method_ || n_free_particles() == 0)
    return 0;
  auto& p = const_cast<meshfree::ParticleSet<dim>&>(particles_);
  method_->update_damage(p, bonds_);
  double m = 0;
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i] && is_owned(i))
      m = std::max(m, particles_.damage(i));
  return Utilities::MPI::max(m, fem_.mpi_communicator());
}

template <int dim>
Tensor<1, dim> FemParticleCoupling<dim>::reaction_force(types::boundary_id id) const {
  const auto& bcs = fem_.boundary_conditions().dirichlet();
  std::set<unsigned int> counted;
  Tensor<1, dim> particles; // owned fixed particles; the support balances their force
  for (const auto& f : impl_->fixed)
    if (bcs[f.slot].boundary_id == id && is_owned(f.particle) && counted.insert(f.particle).second)
      particles -= particles_.force(f.particle);
  // One reduction a call: the peak load reads this every step.
  return Utilities::MPI::sum(fem_.local_reaction_force(id) + particles, fem_.mpi_communicator());
}

template <int dim>
std::string FemParticleCoupling<dim>::write_output(const std::string& directory,
                                                   unsigned int cycle) const {
  const std::string name = "particles_" + Utilities::int_to_string(cycle, 4) + ".vtu";
  synchronise(); // collective: damage and states of every particle on every rank
  if (Utilities::MPI::this_mpi_process(fem_.mpi_communicator()) != 0)
    return name;
  meshfree::ParticleSet<dim> out(particles_.thickness());
  for (unsigned int i = 0; i < particles_.size(); ++i)
    if (free_[i]) {
      const unsigned int k =
          out.add_particle(particles_.reference_position(i), particles_.volume(i));
      out.displacement(k) = particles_.displacement(i);
      out.velocity(k) = particles_.velocity(i);
      out.density(k) = particles_.density(i);
      out.damage(k) = particles_.damage(i);
      out.temperature(k) = particles_.temperature(i);
    }
  const std::string dir =
      directory.empty() || directory.back() == '/' ? directory : directory + "/";
  meshfree::write_particles_vtu(out, dir + name + ".tmp");
  std::rename((dir + name + ".tmp").c_str(), (dir + name).c_str());
  return name;
}

template <int dim>
void FemParticleCoupling<dim>::save(const std::string& file) const {
  // Collective: states from their owners, broken pairs from the rows' owners.
  synchronise();
  const double dissipation = fracture_dissipation();
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  for (unsigned int i = 0; i < bonds_.n_particles(); ++i)
    for (std::size_t k = bonds_.begin(i); k < bonds_.end(i); ++k)
      if (bonds_.broken[k])
        broken.emplace_back(i, bonds_.neighbor[k]);
  if (Utilities::MPI::n_mpi_processes(fem_.mpi_communicator()) > 1) {
    std::vector<std::pair<unsigned int, unsigned int>> all;
    for (const auto& part : Utilities::MPI::all_gather(fem_.mpi_communicator(), broken))
      all.insert(all.end(), part.begin(), part.end());
    broken = std::move(all);
  }
  if (Utilities::MPI::this_mpi_process(fem_.mpi_communicator()) != 0)
    return;
  std::ofstream out(file, std::ios::binary);
  out.precision(17);
  // Version 2 adds the fracture-heat totals (the per-particle accounts are handed to the FEM
  // at the end of every macro step, so they are empty when a checkpoint is written).
  out << "spinesim_coupling 2\n"
      << time_ << " " << particles_.size() << " " << converted_.size() << " " << broken.size()
      << " " << dissipation << " " << fracture_heat_ << "\n";
  for (const auto& [id, batch] : converted_)
    out << id << " " << batch << "\n";
  for (unsigned int i = 0; i < particles_.size(); ++i) {
    out << host_cell_[i] << " " << host_point_[i] << " " << int(free_[i]) << " "
        << impl_->fixed_slots[i] << " " << particles_.volume(i) << " " << particles_.density(i)
        << " " << particles_.temperature(i);
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles_.reference_position(i)[d];
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles_.displacement(i)[d] << " " << particles_.velocity(i)[d];
    out << "\n";
  }
  for (const auto& [i, j] : broken)
    out << i << " " << j << "\n";
}

template <int dim>
void FemParticleCoupling<dim>::load(const std::string& file) {
  prepare();
  impl_->searched_bonds = {}; // the particles are replaced: search them afresh
  impl_->searched_volumes.clear();
  impl_->free_searched.clear(); // every loaded free particle is searched around afresh
  std::ifstream in(file, std::ios::binary);
  std::string tag;
  int version = 0;
  std::size_t n = 0, nc = 0, nb = 0;
  if (!(in >> tag >> version >> time_ >> n >> nc >> nb) || tag != "spinesim_coupling" ||
      (version != 1 && version != 2) ||
      (version == 2 && !(in >> fracture_dissipation_ >> fracture_heat_)))
    throw InvalidInput(file, "missing or unreadable coupling checkpoint",
                       "a file written by FemParticleCoupling::save (versions 1 and 2)");
  if (version == 1)
    fracture_dissipation_ = fracture_heat_ = 0;
  if (Utilities::MPI::this_mpi_process(fem_.mpi_communicator()) != 0)
    fracture_dissipation_ = 0; // the saved total counts once, on rank 0
  fracture_energy_.clear();
  converted_.clear();
  for (std::size_t k = 0; k < nc; ++k) {
    std::string id;
    unsigned int batch;
    in >> id >> batch;
    converted_[id] = batch;
  }
  particles_ = meshfree::ParticleSet<dim>(method_->thickness());
  free_.clear();
  host_cell_.clear();
  host_point_.clear();
  impl_->host_index.clear();
  index_of_.clear();
  impl_->fixed_slots.clear();
  for (std::size_t i = 0; i < n; ++i) {
    std::string id;
    unsigned int q, slots;
    int fr;
    double V, rho, T;
    Point<dim> x;
    Tensor<1, dim> u, v;
    in >> id >> q >> fr >> slots >> V >> rho >> T;
    for (unsigned int d = 0; d < dim; ++d)
      in >> x[d];
    for (unsigned int d = 0; d < dim; ++d)
      in >> u[d] >> v[d];
    const unsigned int k = particles_.add_particle(x, V);
    particles_.density(k) = rho;
    particles_.temperature(k) = T;
    particles_.displacement(k) = u;
    particles_.velocity(k) = v;
    free_.push_back(static_cast<std::uint8_t>(fr));
    add_host(id, q);
    index_of_[{id, q}] = k;
    impl_->fixed_slots.push_back(slots);
  }
  std::set<std::pair<unsigned int, unsigned int>> broken;
  for (std::size_t k = 0; k < nb; ++k) {
    unsigned int i, j;
    if (!(in >> i >> j))
      break;
    broken.emplace(std::min(i, j), std::max(i, j));
  }
  if (!in && !in.eof())
    throw InvalidInput(file, "truncated coupling checkpoint", "a complete checkpoint");
  std::vector<bool> active(fem_.dof_handler().get_triangulation().n_active_cells(), true);
  for (const auto& cell : fem_.dof_handler().active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) && converted_.count(cell->id().to_string()))
      active[cell->active_cell_index()] = false;
  fem_.set_active_cells(active);
  // Rebuild with the saved broken pairs.
  bonds_ = meshfree::BondList<dim>();
  rebuild_interface();
  for (unsigned int i = 0; i < bonds_.n_particles(); ++i)
    for (std::size_t k = bonds_.begin(i); k < bonds_.end(i); ++k)
      if (broken.count({std::min(i, bonds_.neighbor[k]), std::max(i, bonds_.neighbor[k])}))
        bonds_.broken[k] = 1;
}

template class FemParticleCoupling<2>;
template class FemParticleCoupling<3>;

} // namespace spinesim::coupling
