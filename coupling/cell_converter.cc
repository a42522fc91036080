#include "coupling/cell_converter.h"

#include "coupling/coupled_totals.h"
#include "coupling/particle_record.h"
#include "coupling/point_bins.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"
#include "fem/cell_indicators.h"
#include "fem/heat/heat_solver.h"

#include <deal.II/base/mpi.h>
#include <deal.II/fe/fe_values.h>

#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>

namespace spinesim::coupling {

using namespace dealii;

namespace {

// Every rank's cell ids (text form) on every rank, in rank order.
std::vector<CellId> gather_cell_ids(const MPI_Comm comm, const std::vector<std::string>& mine) {
  std::vector<CellId> all;
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& id : part)
      all.emplace_back(id);
  return all;
}

} // namespace

template <int dim>
double ConversionReport<dim>::mass_change_relative() const {
  return std::abs(mass_after - (mass_before - hole_mass)) / std::max(mass_before, 1e-300);
}

template <int dim>
double ConversionReport<dim>::momentum_change_relative() const {
  return (momentum_after - (momentum_before - hole_momentum)).norm() /
         std::max(momentum_before.norm(), 1e-300);
}

template <int dim>
double ConversionReport<dim>::plastic_strain_change_relative() const {
  const double d = std::abs(plastic_strain_after - plastic_strain_before);
  return plastic_strain_before > 0 ? d / plastic_strain_before : d;
}

template <int dim>
double ConversionReport<dim>::reaction_jump_relative() const {
  return std::abs(reaction_after - reaction_before) / std::max(reaction_before, 1e-300);
}

template <int dim>
std::string ConversionReport<dim>::describe(const char* force_unit) const {
  std::ostringstream s;
  s << cells << " cells -> " << particles << " particles (mass change " << mass_change_relative()
    << ", momentum change " << momentum_change_relative() << " relative; kinetic energy moved "
    << kinetic_after - kinetic_before << " J)";
  if (reaction_before > 0 && reaction_after > 0)
    s << "; reactions at equilibrium under the same load (norm over the supported DoFs) "
      << reaction_before << force_unit << " before, " << reaction_after << force_unit
      << " after (relative jump " << reaction_jump_relative() << ")";
  if (carries_state && plastic_strain_before > 0)
    s << "; material state carried: integral of the equivalent plastic strain "
      << plastic_strain_before << " m^3 in the cells, " << plastic_strain_after
      << " m^3 in their particles";
  return s.str();
}

template <int dim>
double ConversionReport<dim>::kinetic_change_relative() const {
  return std::abs(kinetic_after - (kinetic_before - hole_kinetic)) /
         std::max(kinetic_before, 1e-300);
}

template <int dim>
void CellConverter<dim>::prepare_mesh(const CouplingParameters<dim>& p,
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
std::vector<CellId> CellConverter<dim>::initial_cells() const {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  std::vector<std::string> initial;
  bool coarse_in_hole = false; // a cell the hole reaches is off the particle lattice
  for (const auto& [id, cell] : state_.owned_cells) {
    bool inside = state_.prm.all_particles;
    if (!inside && !state_.prm.region_lower.empty()) {
      inside = true;
      const Point<dim> c = cell->center();
      for (unsigned int d = 0; d < dim; ++d)
        inside &= c[d] >= state_.prm.region_lower[d] && c[d] <= state_.prm.region_upper[d];
    }
    // A hole the mesh does not model: the cells it may reach are particles from the start, so
    // no FEM cell carries material inside it (bounding-sphere test, conservative).
    if (state_.prm.has_hole() && state_.prm.distance_from_hole_axis(cell->center()) <
                                     state_.prm.hole_radius + 0.5 * cell->diameter()) {
      inside = true;
      coarse_in_hole |= cell->minimum_vertex_distance() >
                        1.5 * state_.spacing * state_.prm.particles_per_direction;
    }
    if (inside)
      initial.push_back(id);
  }
  // Decided together: a rank alone throwing would leave the others in the gather below.
  if (Utilities::MPI::logical_or(coarse_in_hole, comm))
    throw InvalidInput("Coupling/Hole radius",
                       "the hole reaches cells coarser than the particle lattice (" +
                           std::to_string(state_.spacing) + " m spacing)",
                       "a hole inside the refinement box (Refinement region, Region "
                       "refinements) or on a uniform mesh, with half a cell diagonal to spare");
  return gather_cell_ids(comm, initial);
}

template <int dim>
std::vector<CellId> CellConverter<dim>::flagged_cells() const {
  ScopedTime time(state_.timings.criteria);
  const bool any = state_.prm.principal_strain_threshold > 0 ||
                   state_.prm.plastic_strain_threshold > 0 || state_.prm.min_jacobian_ratio > 0 ||
                   state_.prm.min_time_step > 0;
  std::vector<Point<dim>> centres;
  // Cells near a support stay FEM (Coupling/Support clearance).
  const double clearance = state_.prm.support_clearance;
  const std::vector<Point<dim>> none;
  const PointBins<dim> support_bins(any && clearance > 0 ? support_points() : none,
                                    std::max(clearance, state_.spacing));
  const auto may_convert = [&](const DoFCell& cell) {
    return state_.fem.is_active(cell) && in_conversion_region(cell) &&
           !state_.never_converts(cell) &&
           !(clearance > 0 && support_bins.any_within(cell->center(), clearance));
  };
  if (any) {
    // Only active cells of the particle lattice's size can convert (the refinement box).
    std::vector<bool> candidate(state_.fem.dof_handler().get_triangulation().n_active_cells(),
                                false);
    for (const auto& cell : state_.lattice_cells)
      candidate[cell->active_cell_index()] = may_convert(cell);
    fem::CellIndicators<dim> indicators;
    indicators.compute(state_.fem, state_.prm.plastic_strain_threshold > 0, candidate,
                       state_.prm.min_jacobian_ratio > 0 || state_.prm.min_time_step > 0);
    for (const auto& cell : state_.lattice_cells) {
      if (!candidate[cell->active_cell_index()])
        continue;
      const unsigned int c = cell->active_cell_index();
      bool flag = false;
      flag |= state_.prm.principal_strain_threshold > 0 &&
              indicators.max_principal_strain(c) >= state_.prm.principal_strain_threshold;
      flag |= state_.prm.plastic_strain_threshold > 0 &&
              indicators.equivalent_plastic_strain(c) >= state_.prm.plastic_strain_threshold;
      flag |= state_.prm.min_jacobian_ratio > 0 &&
              indicators.min_jacobian_ratio(c) <= state_.prm.min_jacobian_ratio;
      flag |= state_.prm.min_time_step > 0 &&
              indicators.stable_time_step(c) <= state_.prm.min_time_step;
      if (flag)
        centres.push_back(cell->center());
    }
  }
  const MPI_Comm comm = state_.fem.mpi_communicator();
  std::vector<Point<dim>> all_centres;
  for (const auto& part : Utilities::MPI::all_gather(comm, centres))
    all_centres.insert(all_centres.end(), part.begin(), part.end());
  std::vector<std::string> mine;
  if (!all_centres.empty()) {
    const double reach = std::max(state_.prm.buffer, 1e-9 * state_.spacing);
    PointBins<dim> bins(all_centres, std::max(state_.prm.buffer, state_.spacing));
    for (const auto& cell : state_.lattice_cells)
      if (may_convert(cell) && !bins.within(cell->center(), reach).empty())
        mine.push_back(cell->id().to_string());
  }
  return gather_cell_ids(comm, mine);
}

template <int dim>
const std::vector<Point<dim>>& CellConverter<dim>::support_points() const {
  // The mesh and the conditions are fixed once the coupling is set up: gathered once.
  if (support_points_)
    return *support_points_;
  std::vector<Point<dim>> mine;
  for (const auto& bc : state_.fem.boundary_conditions().dirichlet())
    for (const auto& cell : state_.fem.dof_handler().active_cell_iterators()) {
      if (!cell->is_locally_owned())
        continue;
      if (bc.region) {
        // A region holds the DoFs whose support points (Q1: the vertices) lie in its box,
        // inside the body as well as on its boundary.
        for (const unsigned int v : cell->vertex_indices())
          if (bc.region->contains(cell->vertex(v)))
            mine.push_back(cell->vertex(v));
        continue;
      }
      for (const unsigned int f : cell->face_indices())
        if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == bc.boundary_id) {
          mine.push_back(cell->face(f)->center());
          for (const unsigned int v : cell->face(f)->vertex_indices())
            mine.push_back(cell->face(f)->vertex(v));
        }
    }
  support_points_.emplace();
  for (const auto& part : Utilities::MPI::all_gather(state_.fem.mpi_communicator(), mine))
    support_points_->insert(support_points_->end(), part.begin(), part.end());
  return *support_points_;
}

template <int dim>
bool CellConverter<dim>::in_conversion_region(const DoFCell& cell) const {
  const auto& lo = state_.prm.convert_lower;
  const auto& hi = state_.prm.convert_upper;
  if (lo.empty())
    return true;
  const Point<dim> c = cell->center();
  for (unsigned int d = 0; d < dim; ++d)
    if (c[d] < lo[d] || c[d] > hi[d])
      return false;
  return true;
}

template <int dim>
ConversionReport<dim> CellConverter<dim>::convert_flagged() {
  const auto cells = flagged_cells();
  if (cells.empty())
    return ConversionReport<dim>();
  return convert(cells);
}

template <int dim>
std::vector<ParticleRecord<dim>>
CellConverter<dim>::make_records(const std::set<std::string>& todo, double& max_velocity_scale,
                                 ConversionReport<dim>& hole) const {
  const auto& fe = state_.fem.fe();
  const auto& bcs = state_.fem.boundary_conditions().dirichlet();
  Vector<double> prescribed(dim);
  const bool finite_strain = state_.fem.parameters().kinematics != "small_strain";
  FEValues<dim> at_points(state_.fem.mapping(), fe, state_.points,
                          update_values | update_quadrature_points | update_JxW_values);
  FEValues<dim> at_gauss(state_.fem.mapping(), fe, state_.fem.quadrature(),
                         update_values | update_JxW_values);
  const FEValuesExtractors::Vector disp(0);
  const unsigned int np = state_.points.size();
  std::vector<Tensor<1, dim>> u(np), v(np), vg(state_.fem.quadrature().size());
  std::vector<double> temperature(np, 0.0);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  const auto& hanging = state_.fem.hanging_constraints();
  const auto& velocity = state_.fem.velocity();
  const bool with_state = state_.carries_state();
  if (with_state)
    state_.fem.refresh_states();
  std::vector<ParticleRecord<dim>> mine;
  for (const auto& id : todo) {
    const auto it = state_.owned_cells.find(id);
    if (it == state_.owned_cells.end())
      continue;
    const auto& cell = it->second;
    // PD is calibrated on one lattice spacing: coarser cells would carry a wrong horizon.
    if (cell->minimum_vertex_distance() > 1.5 * state_.spacing * state_.prm.particles_per_direction)
      throw InvalidInput("Coupling/Refinement region lower corner",
                         "a cell of edge " + std::to_string(cell->minimum_vertex_distance()) +
                             " m at (" + std::to_string(cell->center()[0]) + ", " +
                             std::to_string(cell->center()[1]) +
                             ") is to become particles, but the particle lattice is " +
                             std::to_string(state_.spacing) + " m",
                         "a refinement box (with Region refinements) that covers every cell "
                         "the conversion can reach");
    at_points.reinit(cell);
    at_gauss.reinit(cell);
    at_points[disp].get_function_values(state_.fem.displacement(), u);
    at_points[disp].get_function_values(state_.fem.velocity(), v);
    at_gauss[disp].get_function_values(state_.fem.velocity(), vg);
    if (state_.heat)
      state_.heat->temperature_at_unit_points(cell, state_.points.get_points(), temperature);
    const double rho = state_.fem.cell_material(cell).density();
    const materials::LawParameters law = state_.cell_law_parameters(cell);
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
    // Points in a hole make no particle: their share of mass, momentum and kinetic energy (at
    // the unscaled velocities) leaves with the cell and is booked in `hole`. Such a cell keeps
    // λ = 1: the energy match is over the whole cell.
    bool cut_by_hole = false;
    for (unsigned int q = 0; q < np; ++q)
      if (state_.prm.in_hole(at_points.quadrature_point(q))) {
        const double m = rho * at_points.JxW(q) * scale;
        hole.mass_before += m;
        hole.momentum_before += m * (v[q] + dv);
        hole.kinetic_before += 0.5 * m * (v[q] + dv).norm_square();
        cut_by_hole = true;
      }
    double lambda = 1;
    if (state_.prm.conserve_kinetic_energy && !cut_by_hole && fluctuation > 1e-14 * nodal_kinetic &&
        excess > 0)
      lambda = std::sqrt(excess / fluctuation);
    max_velocity_scale = std::max(max_velocity_scale, lambda);
    // The particles of a cell a condition holds by a whole face (its boundary id, or a face
    // inside its region) are held with it. A region that holds only an edge or a vertex of the
    // cell (a pin) holds none of its particles; its FEM nodes stay held while a cell that
    // shares them is FEM.
    std::uint32_t slots = 0;
    for (unsigned int k = 0; k < bcs.size(); ++k)
      for (const unsigned int f : cell->face_indices())
        if (bcs[k].holds_face(cell->face(f)))
          slots |= 1u << k;
    for (unsigned int q = 0; q < np; ++q) {
      if (state_.prm.in_hole(at_points.quadrature_point(q)))
        continue;
      ParticleRecord<dim> r;
      r.cell = id;
      r.point = q;
      r.free = true;
      r.fixed_slots = slots;
      r.volume = at_points.JxW(q) * scale;
      r.density = rho;
      r.law = law;
      r.temperature = temperature[q];
      r.position = at_points.quadrature_point(q);
      r.displacement = u[q];
      // A particle sits inside its cell, not on the boundary face. Under finite strain it
      // keeps the offset from the prescribed value it has when it appears and moves with the
      // prescribed motion after, instead of jumping onto the face's value: a particle of a
      // crushed cell at a wall lies a fraction of a cell from where the face's value would
      // put it. Under small strain the jump is of the order of the strain times the spacing
      // and the particle takes the face's value, as do the cells that are particles from
      // t = 0.
      if (slots != 0 && finite_strain && state_.fem.time() > 0)
        for (unsigned int k = 0; k < bcs.size(); ++k)
          if ((slots >> k) & 1u) {
            bcs[k].function->set_time(state_.fem.time());
            bcs[k].function->vector_value(r.position, prescribed);
            for (unsigned int c = 0; c < dim; ++c)
              if (bcs[k].mask[c])
                r.support_offset[c] = u[q][c] - prescribed[c];
          }
      for (unsigned int d = 0; d < dim; ++d)
        r.velocity[d] = mean[d] + lambda * (v[q][d] + dv[d] - mean[d]);
      if (with_state) {
        r.has_state = true;
        r.state = state_.cell_state(cell, q);
        if (const auto F = state_.cell_state_deformation(cell, q)) {
          r.has_state_deformation = true;
          r.state_deformation = *F;
        }
      }
      mine.push_back(std::move(r));
    }
  }
  return mine;
}

template <int dim>
ConversionReport<dim> CellConverter<dim>::convert(const std::vector<CellId>& cells) {
  ConversionReport<dim> report;
  std::set<std::string> todo;
  for (const auto& id : cells) {
    const std::string s = id.to_string();
    if (!converted_.count(s))
      todo.insert(s);
  }
  report.cells = static_cast<unsigned int>(todo.size());
  if (todo.empty())
    return report;
  const MPI_Comm comm = state_.fem.mpi_communicator();
  // The energy account books what the conversion adds (FemParticleCoupling::energy_balance).
  const bool account = state_.fem.energy_account_on();
  double particles_before = 0, fem_before = 0;
  const auto fem_energy = [&] {
    const double stored = state_.fem.linear_stored_energy();
    return (std::isnan(stored) ? 0.0 : stored) + state_.fem.kinetic_energy();
  };
  {
    ScopedTime time(state_.timings.totals);
    report.mass_before = total_mass(state_);
    report.momentum_before = total_momentum(state_);
    report.kinetic_before = kinetic_energy(state_);
    if (account && splice_energy_) {
      particles_before = splice_energy_();
    } else if (account) {
      // The particles' side as their account counts it (ParticleEnergy: stored energy plus
      // the plastic work carried in their history).
      particles_before = particle_strain_energy(state_) + particle_plastic_work(state_) +
                         particle_kinetic_energy(state_);
      fem_before = fem_energy();
    }
  }
  std::optional<ScopedTime> records_time(state_.timings.records);
  report.carries_state = state_.carries_state();
  if (report.carries_state) {
    state_.fem.refresh_states();
    FEValues<dim> at_gauss(state_.fem.mapping(), state_.fem.fe(), state_.fem.quadrature(),
                           update_JxW_values);
    double integral = 0;
    for (const auto& id : todo) {
      const auto it = state_.owned_cells.find(id);
      if (it == state_.owned_cells.end())
        continue;
      at_gauss.reinit(it->second);
      const auto data = state_.fem.quadrature_point_data(it->second);
      for (unsigned int q = 0; q < data.size(); ++q)
        integral += data[q].state.equivalent_plastic_strain * at_gauss.JxW(q);
    }
    report.plastic_strain_before = Utilities::MPI::sum(integral, comm);
  }

  // Records of the new free particles from the ranks owning their cells.
  ConversionReport<dim> hole;
  const auto mine = make_records(todo, report.max_velocity_scale, hole);
  report.hole_mass = Utilities::MPI::sum(hole.mass_before, comm);
  report.hole_momentum = Utilities::MPI::sum(hole.momentum_before, comm);
  report.hole_kinetic = Utilities::MPI::sum(hole.kinetic_before, comm);
  unsigned int added = 0;
  std::vector<unsigned int> batch_particles;
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& r : part) {
      unsigned int i;
      const auto existing = state_.index_of.find({r.cell, r.point});
      if (existing != state_.index_of.end()) {
        i = existing->second;
      } else {
        i = state_.add_particle(r.cell, r.point, r.position, r.volume);
      }
      state_.free[i] = 1;
      state_.fixed_slots[i] = r.fixed_slots;
      state_.support_offset[i] = r.support_offset;
      state_.particles.volume(i) = r.volume;
      state_.particles.density(i) = r.density;
      state_.particles.material_id(i) = state_.law_index(r.law, state_.owned_law(r.cell));
      state_.particles.temperature(i) = r.temperature;
      state_.particles.displacement(i) = r.displacement;
      state_.particles.velocity(i) = r.velocity;
      if (r.has_state) // the method takes it after the rebuild (BondRows::hand_over_states)
        state_.pending_states.push_back(CouplingState<dim>::carried(i, r));
      batch_particles.push_back(i);
      ++added;
    }
  report.particles = added;
  const unsigned int batch = static_cast<unsigned int>(reports_.size());
  for (const auto& id : todo)
    converted_.emplace(id, batch);

  records_time.reset();
  // Deactivate the converted cells (owned and ghost cells, by CellId).
  std::optional<ScopedTime> deactivation_time(state_.timings.deactivation);
  // The cells converted before are inactive already; of the others only this batch turns.
  std::set<CellId> batch_ids;
  for (const auto& id : todo)
    batch_ids.emplace(id);
  std::vector<bool> active(state_.fem.dof_handler().get_triangulation().n_active_cells(), true);
  for (const auto& cell : state_.fem.dof_handler().active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) &&
        (!state_.fem.is_active(cell) || batch_ids.count(cell->id())))
      active[cell->active_cell_index()] = false;
  state_.fem.set_active_cells(active);
  deactivation_time.reset();
  rebuild_layers_();

  ScopedTime time(state_.timings.totals);
  if (report.carries_state) {
    double integral = 0; // what the particles' families hold now (owners count)
    for (const unsigned int i : batch_particles)
      if (state_.is_owned(i))
        integral +=
            state_.particles.volume(i) * state_.method->particle_state(i).equivalent_plastic_strain;
    report.plastic_strain_after = Utilities::MPI::sum(integral, comm);
  }
  report.max_velocity_scale =
      Utilities::MPI::max(report.max_velocity_scale, state_.fem.mpi_communicator());
  report.mass_after = total_mass(state_);
  report.momentum_after = total_momentum(state_);
  report.kinetic_after = kinetic_energy(state_);
  if (account && splice_energy_) {
    report.energy_change_particles = splice_energy_() - particles_before;
  } else if (account) {
    report.energy_change_particles = particle_strain_energy(state_) +
                                     particle_plastic_work(state_) +
                                     particle_kinetic_energy(state_) - particles_before;
    report.energy_change_fem = fem_energy() - fem_before;
  }
  reports_.push_back(report);
  return report;
}

template <int dim>
double CellConverter<dim>::energy_change_particles() const {
  double sum = restored_energy_particles_; // the same order of additions as without a restart
  for (const auto& r : reports_)
    sum += r.energy_change_particles;
  return sum;
}

template <int dim>
double CellConverter<dim>::energy_change_fem() const {
  double sum = restored_energy_fem_;
  for (const auto& r : reports_)
    sum += r.energy_change_fem;
  return sum;
}

template <int dim>
void CellConverter<dim>::restore(std::map<std::string, unsigned int> converted) {
  converted_ = std::move(converted);
  std::vector<bool> active(state_.fem.dof_handler().get_triangulation().n_active_cells(), true);
  for (const auto& cell : state_.fem.dof_handler().active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) && converted_.count(cell->id().to_string()))
      active[cell->active_cell_index()] = false;
  state_.fem.set_active_cells(active);
}

template struct ConversionReport<2>;
template struct ConversionReport<3>;
template class CellConverter<2>;
template class CellConverter<3>;

} // namespace spinesim::coupling
