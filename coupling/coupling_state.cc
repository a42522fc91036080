#include "coupling/coupling_state.h"

#include "base/exceptions.h"

#include <deal.II/base/array_view.h>
#include <deal.II/base/mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
CouplingState<dim>::CouplingState(const CouplingParameters<dim>& parameters,
                                  fem::MechanicsSolver<dim>& mechanics,
                                  const fem::HeatSolver<dim>* heat_solver)
    : prm(parameters), fem(mechanics), heat(heat_solver),
      points(QMidpoint<1>(), parameters.particles_per_direction),
      particles(1.0) { // 2-D coupled runs are per unit thickness (prepare())
  rank = Utilities::MPI::this_mpi_process(fem.mpi_communicator());
  // The heat solver keeps every cell (it has no inactive cells), so a hole the mesh does not
  // model would still conduct and store heat, and hand that field to the particles.
  if (prm.has_hole() && heat)
    throw InvalidInput("Coupling/Hole radius",
                       "a hole cut from the particles in a run with Effects/Heat: the heat "
                       "equation would still run through the hole",
                       "Hole radius = 0 with heat, or a mesh that models the hole");
  if (fem.parameters().time_integration != "explicit" &&
      fem.parameters().time_integration != "quasi_static")
    throw InvalidInput("Mechanics/Time integration",
                       "coupling runs explicit dynamics or quasi-static relaxation",
                       "explicit or quasi_static");
  if (fem.parameters().fe_degree != 1)
    throw InvalidInput("Mechanics/Finite element degree", "coupling needs Q1 elements",
                       "Finite element degree = 1");
  // Finite strain couples in explicit dynamics: ghosts follow the FEM's material points and
  // their forces return through the same shape functions (a total-Lagrangian virtual work),
  // so nothing in the overlap splice assumes small strain. The energy splice's correction is
  // built from the small-strain tangent, and quasi-static relaxation with finite strain is
  // not verified.
  if (fem.parameters().kinematics != "small_strain") {
    if (fem.parameters().time_integration != "explicit")
      throw InvalidInput("Mechanics/Kinematics",
                         "coupling with finite strain runs explicit dynamics only",
                         "Time integration = explicit with Kinematics = finite_strain, or "
                         "Kinematics = small_strain");
    if (prm.splice == "energy")
      throw InvalidInput("Coupling/Splice",
                         "the energy splice's consistency correction is built from the "
                         "small-strain tangent",
                         "Splice = overlap with Kinematics = finite_strain");
  }
}

template <int dim>
double CouplingState<dim>::horizon() const {
  return method->neighbor_options(spacing).horizon;
}

template <int dim>
unsigned int CouplingState<dim>::n_free_particles() const {
  return static_cast<unsigned int>(std::count(free.begin(), free.end(), 1));
}

template <int dim>
std::vector<std::uint8_t> CouplingState<dim>::in_unconverted_cells() const {
  const unsigned int n = particles.size();
  std::vector<std::uint8_t> in(n, 0);
  if (prm.unconverted_material_ids.empty())
    return in;
  for (unsigned int i = 0; i < n; ++i)
    if (!free[i] && host_index[i] >= 0 && never_converts(owned_by_index[host_index[i]]))
      in[i] = 1;
  const MPI_Comm comm = fem.mpi_communicator();
  if (dealii::Utilities::MPI::n_mpi_processes(comm) > 1) {
    std::vector<unsigned int> flags(in.begin(), in.end());
    dealii::Utilities::MPI::max(flags, comm, flags);
    std::copy(flags.begin(), flags.end(), in.begin());
  }
  return in;
}

template <int dim>
unsigned int CouplingState<dim>::n_ghost_particles() const {
  return static_cast<unsigned int>(free.size()) - n_free_particles();
}

template <int dim>
std::size_t CouplingState<dim>::memory_bytes() const {
  // A string's own buffer beyond the small-string capacity it holds inline.
  const auto string_bytes = [](const std::string& text) {
    return text.capacity() > std::string().capacity() ? text.capacity() + 1 : std::size_t(0);
  };
  // A std::map node: the value and, in libstdc++, three pointers and a colour word.
  constexpr std::size_t map_node = 4 * sizeof(void*);
  std::size_t bytes = particles.memory_bytes() + bonds.memory_bytes() +
                      (method ? method->memory_bytes() : 0) + free.capacity() +
                      driven_gradients.capacity() * sizeof(dealii::Tensor<2, dim>) +
                      host_cell.capacity() * sizeof(std::string) +
                      (host_point.capacity() + fixed_slots.capacity()) * sizeof(std::uint32_t) +
                      (host_index.capacity() + owner.capacity()) * sizeof(int) +
                      support_offset.capacity() * sizeof(dealii::Tensor<1, dim>) +
                      pending_states.capacity() * sizeof(meshfree::CarriedState) +
                      free_cells.capacity() * sizeof(HostRow);
  for (const auto& cell : host_cell)
    bytes += string_bytes(cell);
  for (const auto& [key, index] : index_of)
    bytes += map_node + sizeof(key) + sizeof(index) + string_bytes(key.first);
  for (const auto& [cell, points] : free_cells)
    bytes += points.capacity() * sizeof(int);
  return bytes;
}

template <int dim>
void CouplingState<dim>::prepare() {
  if (method)
    return;
  const auto& dh = fem.dof_handler();
  const auto& fe = fem.fe();
  owned_cells.clear();
  double h_min = std::numeric_limits<double>::max(), h_max = 0;
  bool have_law = false;
  std::shared_ptr<const materials::ConstitutiveLaw> law;
  for (const auto& cell : dh.active_cell_iterators())
    if (cell->is_locally_owned()) {
      owned_cells.emplace(cell->id().to_string(), cell);
      h_min = std::min(h_min, cell->minimum_vertex_distance());
      h_max = std::max(h_max, cell->diameter() / std::sqrt(double(dim)));
      if (!have_law) {
        law = fem.cell_law(cell);
        youngs = law->youngs_modulus();
        poisson = law->poisson_ratio();
        density = law->density();
        have_law = true;
      }
    }
  const MPI_Comm comm = fem.mpi_communicator();
  h_min = Utilities::MPI::min(h_min, comm);
  // E, ν, ρ from the lowest rank that owns cells, and its first cell's law as the method's
  // default law (table entry 0 on every rank, when the law can be described).
  const unsigned int source = Utilities::MPI::min(have_law ? rank : 1u << 30, comm);
  clear_laws();
  {
    std::vector<materials::LawParameters> first(1);
    if (!(have_law && law->describe(first[0])))
      first.clear();
    first = Utilities::MPI::broadcast(comm, first, source);
    if (!first.empty())
      law = laws->law_pointer(law_index(first[0], rank == source ? law : nullptr));
  }
  std::vector<double> props{youngs, poisson, density};
  props = Utilities::MPI::broadcast(comm, props, source);
  youngs = props[0];
  poisson = props[1];
  density = props[2];
  // The lattice spacing of the particles (uniform meshes: cell edge / n).
  spacing = h_min / prm.particles_per_direction;
  owned_by_index.assign(dh.get_triangulation().n_active_cells(), DoFCell());
  for (const auto& [id, cell] : owned_cells)
    owned_by_index[cell->active_cell_index()] = cell;
  lattice_cells.clear();
  for (const auto& cell : owned_by_index)
    if (cell.state() == IteratorState::valid &&
        cell->minimum_vertex_distance() <= 1.5 * spacing * prm.particles_per_direction)
      lattice_cells.push_back(cell);

  // The particles of a cell sit on its sub-cell centres: one spacing serves the lattice only if
  // the cells that can convert are cubes (squares); others give an anisotropic lattice whose
  // horizon, volumes and interface fit are wrong (the patch test fails by percents).
  double worst = 1;
  std::string worst_shape;
  for (const auto& cell : lattice_cells) {
    double lo = cell->extent_in_direction(0), hi = lo;
    for (unsigned int d = 1; d < dim; ++d) {
      lo = std::min(lo, cell->extent_in_direction(d));
      hi = std::max(hi, cell->extent_in_direction(d));
    }
    if (hi / lo > worst) {
      worst = hi / lo;
      std::ostringstream shape_text;
      for (unsigned int d = 0; d < dim; ++d)
        shape_text << (d ? " x " : "") << cell->extent_in_direction(d);
      worst_shape = shape_text.str();
    }
  }
  const double worst_all = Utilities::MPI::max(worst, comm);
  if (worst_all > 1.01) {
    if (worst != worst_all)
      worst_shape = "cells";
    throw InvalidInput("Geometry/Subdivisions",
                       "the cells particles are made from are not cubes (" + worst_shape +
                           " m, aspect ratio " + std::to_string(worst_all) + ")",
                       "cubic (2-D: square) cells where particles can appear: Subdivisions in "
                       "proportion to Lengths");
  }

  shape.reinit(points.size(), fe.n_dofs_per_cell());
  for (unsigned int q = 0; q < points.size(); ++q)
    for (unsigned int i = 0; i < fe.n_dofs_per_cell(); ++i)
      shape(q, i) = fe.shape_value(i, points.point(q));
  // Nearest quadrature point in the unit cell (affine cells: nearest in space as well).
  const auto& gauss = fem.quadrature();
  nearest_quadrature_point.assign(points.size(), 0);
  for (unsigned int q = 0; q < points.size(); ++q)
    for (unsigned int g = 1; g < gauss.size(); ++g)
      if (gauss.point(g).distance(points.point(q)) <
          gauss.point(nearest_quadrature_point[q]).distance(points.point(q)) - 1e-12)
        nearest_quadrature_point[q] = g;

  if (!prm.make_method)
    throw InvalidInput("Coupling", "no particle method was read for the coupling",
                       "Coupling parameters parsed with Effects/Particles method");
  // The method's default law (above); each particle runs its host cell's law from `laws`.
  // Only a law that cannot describe itself leaves a rank without cells to take the first
  // cell's law of the mesh (every rank holds the laws of all material ids).
  if (!law)
    law = fem.cell_law(*dh.active_cell_iterators().begin());
  // The reference temperature is set below.
  meshfree::ParticleMaterial material{youngs, poisson, density, law, 0.0, laws};
  // Particles strain thermally exactly where the FEM does: without a temperature field the
  // FEM ignores the law's expansion coefficient, and so must the particles (their temperatures
  // still follow the heat equation when it runs).
  material.reference_temperature = fem.has_temperature_field()
                                       ? fem.reference_temperature()
                                       : std::numeric_limits<double>::quiet_NaN();
  method = prm.make_method(material);
  particle_material = material;
  for (auto& m : method->take_messages())
    messages.push_back(std::move(m));
  const std::string section =
      "Coupling/" + meshfree::ParticleMethods::instance()
                        .get(prm.particles_method, "Effects/Particles method")
                        .section;
  if (dim == 2 && method->plane_stress() != fem.parameters().plane_stress)
    throw InvalidInput(method->plane_stress() ? "Mechanics/Plane stress" : section,
                       std::string("the particles (") + prm.particles_method + ") are plane " +
                           (method->plane_stress() ? "stress" : "strain") +
                           " but the FEM is plane " +
                           (fem.parameters().plane_stress ? "stress" : "strain"),
                       prm.particles_method == "bond_based"
                           ? "the same model on both sides (Bond based/Plane model and "
                             "Mechanics/Plane stress)"
                           : "Mechanics/Plane stress = false (" + prm.particles_method +
                                 " is plane strain in 2-D)");
  if (!method->carries_material_state() && law->name() != "linear_elastic")
    messages.push_back(prm.particles_method +
                       " particles carry no constitutive state: the "
                       "plastic strain and hardening of converted cells end at conversion (" +
                       law->name() + " in the FEM); nosb or spg continue them");
  if (!prm.damage && !method->user_failure_criteria().empty())
    messages.push_back("Effects/Damage = false: no bond breaks, so the particles' failure "
                       "criteria are not applied (" +
                       method->user_failure_criteria() + ")");
  if (dim == 2 && method->thickness() != 1.0)
    throw InvalidInput(section + "/Thickness", "2-D FEM works per unit thickness",
                       "1 (results are per metre of thickness) [m]");
}

template <int dim>
materials::MaterialState CouplingState<dim>::cell_state(const DoFCell& cell,
                                                        unsigned int point) const {
  return fem.quadrature_point_data(cell)[nearest_quadrature_point[point]].state;
}

template <int dim>
std::optional<materials::Tensor2>
CouplingState<dim>::cell_state_deformation(const DoFCell& cell, unsigned int point) const {
  if (fem.parameters().kinematics == "small_strain")
    return std::nullopt; // a small-strain state is not tied to an F
  // At the current displacement, where the particles' families measure theirs (the point
  // states hold the F of the last force pass, one step behind); an inverted cell: none.
  const auto F = fem.current_deformation_gradients(cell);
  if (!F)
    return std::nullopt;
  return (*F)[nearest_quadrature_point[point]];
}

namespace {
// Exact identity of a law's parameters as a map key: the model and the values' bits.
std::string law_key(const materials::LawParameters& p) {
  const auto values = p.values();
  std::string key = p.model;
  key.push_back(p.secant_tangent ? '\1' : '\0');
  key.append(reinterpret_cast<const char*>(values.data()), sizeof(double) * values.size());
  return key;
}
} // namespace

template <int dim>
unsigned int
CouplingState<dim>::law_index(const materials::LawParameters& p,
                              std::shared_ptr<const materials::ConstitutiveLaw> local) {
  const auto [it, added] = law_lookup.emplace(law_key(p), laws->size());
  if (added) {
    if (method && laws->size() >= 1 && !method->supports_material_table())
      throw InvalidInput("Effects/Particles method",
                         method->name() + " particles take one law, but cells of a second (" +
                             p.describe() + ") turn into particles or ghosts",
                         "nosb, spg or bond_based (a law per particle), or one material");
    laws->add(local ? std::move(local)
                    : std::shared_ptr<const materials::ConstitutiveLaw>(materials::rebuild_law(p)));
    law_parameters.push_back(p);
  }
  return it->second;
}

template <int dim>
materials::LawParameters CouplingState<dim>::cell_law_parameters(const DoFCell& cell) const {
  materials::LawParameters p;
  const auto law = fem.cell_law(cell);
  if (!law->describe(p))
    throw InvalidInput("Material",
                       "law " + law->name() +
                           " cannot be handed to particles (it does not report its parameters)",
                       "a law made from Material parameters (Model)");
  return p;
}

template <int dim>
std::shared_ptr<const materials::ConstitutiveLaw>
CouplingState<dim>::owned_law(const std::string& cell_id) const {
  const auto it = owned_cells.find(cell_id);
  return it == owned_cells.end() ? nullptr : fem.cell_law(it->second);
}

template <int dim>
void CouplingState<dim>::clear_laws() {
  laws->clear();
  law_parameters.clear();
  law_lookup.clear();
}

template <int dim>
unsigned int CouplingState<dim>::add_particle(const std::string& cell_id, unsigned int point,
                                              const Point<dim>& position, double volume) {
  const unsigned int i = particles.add_particle(position, volume);
  index_of[{cell_id, point}] = i;
  free.push_back(0);
  host_cell.push_back(cell_id);
  host_point.push_back(point);
  const auto it = owned_cells.find(cell_id);
  host_index.push_back(it == owned_cells.end() ? -1
                                               : static_cast<int>(it->second->active_cell_index()));
  fixed_slots.push_back(0);
  support_offset.emplace_back();
  driven_gradients.push_back(unit_symmetric_tensor<dim>());
  return i;
}

template <int dim>
void CouplingState<dim>::clear_particles() {
  particles = meshfree::ParticleSet<dim>(method->thickness());
  free.clear();
  host_cell.clear();
  host_point.clear();
  host_index.clear();
  index_of.clear();
  fixed_slots.clear();
  support_offset.clear();
  driven_gradients.clear();
}

template struct CouplingState<2>;
template struct CouplingState<3>;

} // namespace spinesim::coupling
