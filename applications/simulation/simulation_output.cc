#include "applications/simulation/simulation_scenario.h"

#include "fem/displacement_error.h"
#include "meshfree/displacement_error.h"

#include <deal.II/base/mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spinesim::applications {

using namespace framework;
using coupling::FemParticleCoupling;

namespace {

// The particles the crack output looks at: reference positions, damage, which of them count,
// and their keys. A coupled run: the free particles, either those this rank owns (damage
// current there, no communication: history rows) or all of them after synchronising every
// particle's damage to every rank (collective: the end of the run). A zone held whole on every
// rank: all its particles. A distributed zone: its owned particles keyed by lattice id, or at
// the end of the run every rank's cracked particles gathered (collective).
template <int dim>
struct CrackView {
  const std::vector<dealii::Point<dim>>* positions = nullptr;
  const std::vector<double>* damage = nullptr;
  std::vector<std::uint8_t> counted;
  const std::vector<std::uint64_t>* keys = nullptr;
  // Storage of a gathered view.
  std::vector<dealii::Point<dim>> gathered_positions;
  std::vector<double> gathered_damage;
  std::vector<std::uint64_t> gathered_keys;
};

template <int dim>
void fill_crack_view(CrackView<dim>& v, const FemParticleCoupling<dim>* coupled,
                     const ParticleZone<dim>* zone, bool owned_only, double threshold,
                     MPI_Comm comm) {
  if (coupled) {
    if (!owned_only)
      coupled->synchronise();
    const auto& p = coupled->particles();
    v.positions = &p.reference_positions();
    v.damage = &p.damages();
    v.counted.resize(p.size());
    for (unsigned int i = 0; i < p.size(); ++i)
      v.counted[i] = coupled->is_free(i) && (!owned_only || coupled->is_owned(i));
    return;
  }
  const auto& p = zone->particles();
  if (!zone->distributed() || owned_only) {
    v.positions = &p.reference_positions();
    v.damage = &p.damages();
    v.counted.resize(p.size());
    for (unsigned int i = 0; i < p.size(); ++i)
      v.counted[i] = zone->is_owned(i);
    v.keys = zone->global_ids();
    return;
  }
  // key, coordinates, damage of each cracked owned particle, as doubles (keys < 2^53)
  std::vector<double> mine;
  for (unsigned int i = 0; i < p.size(); ++i)
    if (zone->is_owned(i) && p.damage(i) >= threshold) {
      mine.push_back(double((*zone->global_ids())[i]));
      for (unsigned int d = 0; d < dim; ++d)
        mine.push_back(p.reference_position(i)[d]);
      mine.push_back(p.damage(i));
    }
  // Sorted by key: the order of the undistributed zone, so the figures' sums match it.
  std::vector<std::pair<std::uint64_t, const double*>> entries;
  const auto parts = dealii::Utilities::MPI::all_gather(comm, mine);
  for (const auto& part : parts)
    for (std::size_t k = 0; k + dim + 2 <= part.size(); k += dim + 2)
      entries.emplace_back(static_cast<std::uint64_t>(part[k]), &part[k]);
  std::sort(entries.begin(), entries.end());
  for (const auto& [key, entry] : entries) {
    v.gathered_keys.push_back(key);
    dealii::Point<dim> x;
    for (unsigned int d = 0; d < dim; ++d)
      x[d] = entry[1 + d];
    v.gathered_positions.push_back(x);
    v.gathered_damage.push_back(entry[1 + dim]);
  }
  v.positions = &v.gathered_positions;
  v.damage = &v.gathered_damage;
  v.counted.assign(v.gathered_positions.size(), 1);
  v.keys = &v.gathered_keys;
}

} // namespace

template <int dim>
fem::EnergyBalance Simulation<dim>::energy_balance() const {
  if (particles_ && !mechanics_) // summed over the ranks when the zone is distributed
    return particles_->energy_balance();
  fem::EnergyBalance b = coupled_ ? coupled_->energy_balance()
                                  : fem::sum_energy({&mechanics_->energy_account()}, 0.0,
                                                    mechanics_->mpi_communicator());
  b.initial_energy += initial_kinetic_energy_;
  return b;
}

template <int dim>
void Simulation<dim>::record(unsigned int step, double time, RunContext& ctx) {
  dealii::TimerOutput::Scope scope(ctx.timer(), "history");
  last_recorded_time_ = time;
  History::Row row{{"step", step}, {"time", time}, {"load_factor", time / sim_.end_time}};
  if (mechanics_) {
    if (sim_.reaction_boundary_id >= 0) {
      const auto r = coupled_ ? coupled_->reaction_force(sim_.reaction_boundary_id)
                              : mechanics_->reaction_force(sim_.reaction_boundary_id);
      const char* names[] = {"reaction_x", "reaction_y", "reaction_z"};
      for (unsigned int d = 0; d < dim; ++d)
        row.emplace_back(names[d], r[d]);
      track_load(r.norm(), time);
    }
    // Coupled: the FEM's active cells plus the bonds of the free particles.
    row.emplace_back("strain_energy",
                     coupled_ ? coupled_->strain_energy() : mechanics_->strain_energy());
    row.emplace_back("max_von_mises", mechanics_->max_von_mises());
    row.emplace_back("max_displacement", mechanics_->displacement().linfty_norm());
  }
  if (heat_) {
    row.emplace_back("max_temperature", heat_->max_temperature());
    row.emplace_back("heat_content", heat_->heat_content());
  }
  if (particles_)
    particles_->add_history(row);
  if (coupled_) {
    row.emplace_back("free_particles", coupled_->n_free_particles());
    row.emplace_back("converted_cells", coupled_->n_converted_cells());
    row.emplace_back("broken_bonds", double(coupled_->n_broken_bonds()));
    if (const auto contacts = coupled_->n_short_range_contacts())
      row.emplace_back("short_range_contacts", double(*contacts));
    row.emplace_back("max_damage", coupled_->max_damage());
    row.emplace_back("kinetic_energy", coupled_->kinetic_energy());
    if (quasi_static_) {
      row.emplace_back("relaxation_iterations", last_relaxation_.iterations);
      row.emplace_back("relaxation_relative_residual", last_relaxation_.relative_residual);
      row.emplace_back("relaxation_sub_steps", last_step_sub_steps_);
      if (coupled_->carries_material_state()) {
        // The static balance of both models together (FemParticleCoupling::virial_balance).
        const auto balance = coupled_->virial_balance(); // collective
        const double imbalance = balance.imbalance_relative;
        row.emplace_back("virial_imbalance_relative", imbalance);
        row.emplace_back("unbalanced_force", balance.net_force.norm());
        if (!(imbalance <= virial_imbalance_warning))
          ctx.log() << "  warning: t = " << time << " s: the stress both models carry is "
                    << 100 * imbalance
                    << " % off the forces on the body (virial_imbalance_relative): the "
                       "particles carry a load the FEM does not see, or the other way round; "
                       "with NOSB-PD see Coupling/Ghost gradient (docs/coupling.md)"
                    << std::endl;
      }
    }
    if (heat_) {
      row.emplace_back("fracture_dissipation", coupled_->fracture_dissipation());
      row.emplace_back("fracture_heat", coupled_->fracture_heat());
    }
  }
  if (sim_.energy_account) {
    // At the force pass of the step's last explicit step (energy_time = time − dt); the
    // empty account (zeros) before the first step.
    const auto b = energy_balance();
    const auto value = [](double x) { return x; };
    row.emplace_back("energy_time", value(b.time));
    row.emplace_back("external_work_J", value(b.external_work));
    if (particles_ || !sim_.initial_velocity.empty())
      row.emplace_back("initial_energy_J", value(b.initial_energy));
    row.emplace_back("strain_energy_J", value(b.strain_energy));
    row.emplace_back("kinetic_energy_J", value(b.kinetic_energy));
    row.emplace_back("fracture_dissipation_J", value(b.fracture_dissipation));
    row.emplace_back("damping_dissipation_J", value(b.damping_dissipation));
    row.emplace_back("energy_balance_error_relative", value(b.error_relative()));
    row.emplace_back("energy_defect_central_J", value(b.defect_central()));
    if (coupled_) {
      row.emplace_back("interface_work_fem_J", value(b.interface_work));
      row.emplace_back("interface_work_particles_J", value(b.interface_work_particles));
      row.emplace_back("conversion_energy_J", value(b.conversion_energy));
    }
  }
  if (crack_ && (coupled_ || particles_)) { // damage is current: max_damage / add_history
    CrackView<dim> view;
    fill_crack_view<dim>(view, coupled_.get(), particles_.get(), true, crack_->damage_threshold(),
                         ctx.comm());
    crack_->update(*view.positions, *view.damage, view.counted, time, view.keys);
  }
  ctx.history().add(row);
}

template <int dim>
void Simulation<dim>::write_output(unsigned int step, double time, RunContext& ctx) {
  if (!sim_.write_vtu)
    return;
  dealii::TimerOutput::Scope scope(ctx.timer(), "output");
  const std::string dir = ctx.output().path().string();
  if (mechanics_) {
    solution_pvd_.add(time, mechanics_->write_output(dir, "solution", output_cycle_));
    solution_pvd_.write(ctx);
  }
  if (heat_) {
    temperature_pvd_.add(time, heat_->write_output(dir, output_cycle_, "temperature"));
    temperature_pvd_.write(ctx);
  }
  if (coupled_) {
    particles_pvd_.add(time, coupled_->write_output(dir, output_cycle_));
    particles_pvd_.write(ctx);
  }
  if (particles_) {
    std::string name;
    if (ctx.is_root() || particles_->distributed()) // distributed: a piece per rank
      name = particles_->write_output(dir, output_cycle_);
    particles_pvd_.add(time, name);
    particles_pvd_.write(ctx);
  }
  ++output_cycle_;
  (void)step;
}

template <int dim>
void Simulation<dim>::report_figures(RunContext& ctx) {
  Summary& s = ctx.summary();
  s.set_figure("steps", sim_.steps, "-");
  if (triangulation_)
    s.set_figure("cells", triangulation_->n_global_active_cells(), "-");
  if (particles_)
    particles_->add_figures(ctx);
  if (crack_ && (coupled_ || particles_)) {
    CrackView<dim> view; // collective
    fill_crack_view<dim>(view, coupled_.get(), particles_.get(), false, crack_->damage_threshold(),
                         ctx.comm());
    crack_->add_figures(s, *view.positions, *view.damage, view.counted, ctx.comm(),
                        view.keys); // collective
    const std::string csv = crack_->csv(*view.positions, *view.damage, ctx.comm(), view.keys);
    if (ctx.is_root())
      ctx.output().write_atomic("crack_path.csv", csv);
  }
  if (ct_block_) {
    const MPI_Comm comm = mechanics_->mpi_communicator();
    s.set_figure("ct_block_min_modulus_MPa",
                 dealii::Utilities::MPI::min(ct_block_->minimum_modulus(), comm) / 1e6, "MPa");
    s.set_figure("ct_block_max_modulus_MPa",
                 dealii::Utilities::MPI::max(ct_block_->maximum_modulus(), comm) / 1e6, "MPa");
  }
  if (ct_model_) { // every rank built the whole model
    s.set_figure("ct_bone_min_modulus_MPa", ct_model_->minimum_bone_modulus() / 1e6, "MPa");
    s.set_figure("ct_bone_max_modulus_MPa", ct_model_->maximum_bone_modulus() / 1e6, "MPa");
  }
  if (mechanics_ && sim_.reaction_boundary_id >= 0) {
    // The force-displacement curve's peak: when, and how far the load fell after it.
    s.set_figure("peak_load_time_s", peak_time_, "s");
    s.set_figure("post_peak_drop", peak_load_ > 0 ? 1.0 - last_load_ / peak_load_ : 0.0, "-");
    if (!coupled_)
      s.set_figure("peak_load_N", peak_load_, dim == 2 ? "N/m" : "N");
  }
  if (particles_ && particles_->has_reaction()) { // Particles/Reaction region
    s.set_figure("peak_load_N", peak_load_, dim == 2 ? "N/m" : "N");
    s.set_figure("peak_load_time_s", peak_time_, "s");
    s.set_figure("post_peak_drop", peak_load_ > 0 ? 1.0 - last_load_ / peak_load_ : 0.0, "-");
    if (sim_.critical_load_estimate > 0)
      s.set_figure("griffith_ratio", peak_load_ / sim_.critical_load_estimate, "-");
  }
  if (coupled_) {
    const char* force_unit = dim == 2 ? "N/m" : "N";
    s.set_figure("peak_load_N", peak_load_, force_unit);
    if (sim_.critical_load_estimate > 0)
      s.set_figure("griffith_ratio", peak_load_ / sim_.critical_load_estimate, "-");
    s.set_figure("free_particles", coupled_->n_free_particles(), "-");
    s.set_figure("ghost_particles", coupled_->n_ghost_particles(), "-");
    s.set_figure("particle_laws", coupled_->n_particle_laws(), "-");
    s.set_figure("converted_cells", coupled_->n_converted_cells(), "-");
    s.set_figure("broken_bonds", double(coupled_->n_broken_bonds()), "-");
    if (const auto contacts = coupled_->n_short_range_contacts())
      s.set_figure("short_range_contacts", double(*contacts), "-");
    s.set_figure("max_damage", coupled_->max_damage(), "-");
    s.set_figure("explicit_steps", explicit_steps_, "iterations");
    // The particle method's own cost: its force passes (relaxation pseudo-steps included).
    s.set_figure("particle_force_time_s", coupled_->particle_force_seconds(), "s");
    s.set_figure("particle_updates_per_s", coupled_->particle_updates_per_second(), "1/s");
    // Coupled runs keep every particle record on every rank (docs/scaling.md): this figure
    // does not fall with the ranks as a particle zone's does.
    s.set_figure("particle_memory_per_rank_max_bytes",
                 coupled_->particle_memory_per_rank_max_bytes(), "B");
    const ConversionExtremes c = conversion_extremes();
    s.set_figure("conversion_mass_change_relative", c.mass, "-");
    s.set_figure("conversion_momentum_change_relative", c.momentum, "-");
    s.set_figure("conversion_kinetic_energy_change_relative", c.kinetic, "-");
    s.set_figure("conversion_max_velocity_scale", c.velocity_scale, "-");
    if (c.plastic_strain >= 0)
      s.set_figure("conversion_plastic_strain_error_relative", c.plastic_strain, "-");
    if (c.reaction_jump >= 0)
      s.set_figure("conversion_reaction_jump_relative", c.reaction_jump, "-");
    if (coupled_->parameters().has_hole()) // the material the FEM had in the hole, not the body's
      s.set_figure("hole_mass_kg", c.hole_mass, dim == 2 ? "kg/m" : "kg");
    const auto& t = coupled_->timings();
    for (const auto& [name, value] : {std::pair<const char*, double>{"criteria", t.criteria},
                                      {"records", t.records},
                                      {"deactivation", t.deactivation},
                                      {"ghosts", t.ghosts},
                                      {"bonds", t.bonds},
                                      {"interface", t.interface},
                                      {"totals", t.totals}})
      s.set_figure(std::string("conversion_time_") + name + "_s", value, "s");
    if (quasi_static_) {
      s.set_figure("relaxation_iterations", double(relaxation_iterations_), "iterations");
      s.set_figure("relaxation_relative_residual", last_relaxation_.relative_residual, "-");
      // Coupling/Relaxation step cuts: how often a step was cut, and the converged load
      // increments of the run (the steps when nothing was cut).
      s.set_figure("relaxation_step_cuts", double(relaxation_step_cuts_), "-");
      s.set_figure("relaxation_sub_steps", double(relaxation_sub_steps_), "-");
      // Coupling/Break bonds = at equilibrium: equilibria at which bonds broke (each relaxed
      // again at the same load), undone attempts included.
      if (coupling_prm_.relaxation_breaks_at_equilibrium)
        s.set_figure("relaxation_breaking_passes", double(relaxation_breaking_passes_), "-");
      // What holding the states for the cuts costs (FemParticleCoupling::relax_step).
      s.set_figure("step_snapshot_time_s", coupled_->timings().snapshots, "s");
      const auto& history = ctx.history();
      const auto& columns = history.columns();
      const std::string column = "virial_imbalance_relative";
      if (history.size() > 0 &&
          std::find(columns.begin(), columns.end(), column) != columns.end()) {
        // The largest over the recorded steps (NaN if any step's is), and the last step's.
        double largest = 0;
        for (std::size_t r = 0; r < history.size(); ++r) {
          const double v = history.value(r, column);
          largest = std::isnan(v) || std::isnan(largest) ? std::numeric_limits<double>::quiet_NaN()
                                                         : std::max(largest, v);
        }
        s.set_figure("virial_imbalance_relative_max", largest, "-");
        s.set_figure("virial_imbalance_relative", history.value(history.size() - 1, column), "-");
        s.set_figure("unbalanced_force_N", history.value(history.size() - 1, "unbalanced_force"),
                     dim == 2 ? "N/m" : "N");
      }
    }
    s.set_figure("particle_spacing_m", coupled_->particle_spacing(), "m");
    if (coupled_->n_free_particles() > 0 && coupled_->carries_material_state()) {
      // Von Mises stress of the free particles (the particle VTU's von_mises_stress); a failed
      // family carries none (0), a law that failed gives NaN.
      const std::vector<double> sigma = coupled_->cauchy_stresses(); // collective
      const auto& free = coupled_->free_flags();
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (std::size_t i = 0; i < free.size(); ++i) {
        if (!free[i])
          continue;
        const double vm = coupling::FemParticleCoupling<dim>::von_mises(&sigma[6 * i]);
        lo = std::isnan(vm) ? vm : std::min(lo, vm);
        hi = std::isnan(vm) ? vm : std::max(hi, vm);
        if (std::isnan(vm))
          break;
      }
      s.set_figure("particle_max_von_mises", hi, "Pa");
      s.set_figure("particle_min_von_mises", lo, "Pa");
    }
  }
  if (mechanics_) {
    s.set_figure("mechanics_dofs", mechanics_->dof_handler().n_dofs(), "-");
    // The resolution's length, what a convergence study plots its errors against.
    s.set_figure("max_cell_diameter_m",
                 dealii::Utilities::MPI::max(fem::max_cell_diameter(*mechanics_), ctx.comm()), "m");
    s.set_figure("strain_energy",
                 coupled_ ? coupled_->strain_energy() : mechanics_->strain_energy(),
                 dim == 2 ? "J/m" : "J");
    s.set_figure("max_von_mises", mechanics_->max_von_mises(), "Pa");
    s.set_figure("max_displacement", mechanics_->displacement().linfty_norm(), "m");
    if (sim_.reaction_boundary_id >= 0) {
      const auto r = coupled_ ? coupled_->reaction_force(sim_.reaction_boundary_id)
                              : mechanics_->reaction_force(sim_.reaction_boundary_id);
      s.set_figure("reaction_force_norm", r.norm(), dim == 2 ? "N/m" : "N");
      const char* names[] = {"reaction_force_x", "reaction_force_y", "reaction_force_z"};
      for (unsigned int d = 0; d < dim; ++d)
        s.set_figure(names[d], r[d], dim == 2 ? "N/m" : "N");
    }
    s.set_figure("newton_iterations", newton_iterations_, "iterations");
    s.set_figure("linear_iterations", linear_iterations_, "iterations");
  }
  if (sim_.energy_account) {
    // FEM and coupled runs: the account at the last force pass (one explicit step before the
    // end); a particle zone: at the end of its last step. 2-D plane models per unit thickness
    // (a particle zone: per its Thickness). Not valid (no step yet): NaN, which fails every
    // check.
    const auto b = energy_balance();
    const char* unit = dim == 2 ? "J/m" : "J";
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const auto value = [&](double x) { return b.valid ? x : nan; };
    s.set_figure("energy_time_s", value(b.time), "s");
    s.set_figure("external_work_J", value(b.external_work), unit);
    s.set_figure("initial_energy_J", value(b.initial_energy), unit);
    s.set_figure("strain_energy_J", value(b.strain_energy), unit);
    s.set_figure("kinetic_energy_J", value(b.kinetic_energy), unit);
    s.set_figure("fracture_dissipation_J", value(b.fracture_dissipation), unit);
    s.set_figure("damping_dissipation_J", value(b.damping_dissipation), unit);
    s.set_figure("energy_balance_error_relative", value(b.error_relative()), "-");
    s.set_figure("energy_defect_central_J", value(b.defect_central()), unit);
    s.set_figure("energy_defect_central_relative",
                 value(std::abs(b.defect_central()) /
                       std::max(std::abs(b.supplied()), b.stored_and_dissipated())),
                 "-");
    if (coupled_) {
      s.set_figure("interface_work_fem_J", value(b.interface_work), unit);
      s.set_figure("interface_work_particles_J", value(b.interface_work_particles), unit);
      s.set_figure("conversion_energy_J", value(b.conversion_energy), unit);
      s.set_figure("energy_account_time_s", coupled_->energy_account_seconds(), "s");
    }
  }
  if (exact_displacement_)
    report_exact_error(ctx);
  if (heat_) {
    s.set_figure("heat_dofs", heat_->dof_handler().n_dofs(), "-");
    s.set_figure("max_temperature", heat_->max_temperature(), "K");
    s.set_figure("heat_content", heat_->heat_content(), dim == 2 ? "J/m" : "J");
    s.set_figure("heat_supplied_energy", heat_->supplied_energy(), dim == 2 ? "J/m" : "J");
    if (coupled_) {
      // Particle heat sources: the energy of broken bonds, handed to the FEM heat equation one
      // macro step later (staggered), so the last step's share is not yet in the body.
      s.set_figure("fracture_dissipation", coupled_->fracture_dissipation(),
                   dim == 2 ? "J/m" : "J");
      s.set_figure("fracture_heat_applied", fracture_heat_applied_, dim == 2 ? "J/m" : "J");
      // Fracture heat alone against what was supplied: when it is the only internal source.
      if (fracture_heat_applied_ > 0 && particle_plastic_heat_applied_ == 0 &&
          fem_plastic_heat_applied_ == 0)
        s.set_figure("fracture_heat_supplied_relative",
                     std::abs(heat_->supplied_energy() - fracture_heat_applied_) /
                         fracture_heat_applied_,
                     "-");
      // The particles' plastic work × β: handed over so far (the last step's share heats the
      // next step) against the work the free particles did since they became free.
      if (coupled_->particle_plastic_heat_work() > 0) {
        s.set_figure("particle_plastic_heat_J", coupled_->particle_plastic_heat(),
                     dim == 2 ? "J/m" : "J");
        s.set_figure("particle_plastic_heat_applied_J", particle_plastic_heat_applied_,
                     dim == 2 ? "J/m" : "J");
        s.set_figure("particle_plastic_work_heated_J", coupled_->particle_plastic_heat_work(),
                     dim == 2 ? "J/m" : "J");
        s.set_figure("particle_plastic_work_J", coupled_->particle_plastic_work(),
                     dim == 2 ? "J/m" : "J");
      }
    }
    if (mech_prm_.taylor_quinney > 0 && mechanics_)
      s.set_figure("fem_plastic_heat_applied_J", fem_plastic_heat_applied_, dim == 2 ? "J/m" : "J");
    // The internal sources together (fracture, plastic work of the FEM and of the particles)
    // against what the heat solver supplied: equal when the scene has no heat input of its own.
    const double internal =
        fracture_heat_applied_ + particle_plastic_heat_applied_ + fem_plastic_heat_applied_;
    if (internal > 0)
      s.set_figure("internal_heat_supplied_relative",
                   std::abs(heat_->supplied_energy() - internal) / internal, "-");
    // Energy conservation: what the sources supplied is what the body gained (heat through
    // fixed-temperature boundaries is not counted by the solver, so scenes with such
    // boundaries do not balance).
    const double gained = heat_->heat_content() - initial_heat_content_;
    if (heat_->supplied_energy() != 0)
      s.set_figure("heat_energy_balance_relative",
                   std::abs(gained - heat_->supplied_energy()) / std::abs(heat_->supplied_energy()),
                   "-");
  }
}

template <int dim>
typename Simulation<dim>::ConversionExtremes Simulation<dim>::conversion_extremes() const {
  ConversionExtremes c = restored_conversion_extremes_;
  if (coupled_)
    for (const auto& r : coupled_->conversions()) {
      c.mass = std::max(c.mass, r.mass_change_relative());
      c.momentum = std::max(c.momentum, r.momentum_change_relative());
      c.kinetic = std::max(c.kinetic, r.kinetic_change_relative());
      c.velocity_scale = std::max(c.velocity_scale, r.max_velocity_scale);
      c.hole_mass += r.hole_mass;
      if (r.carries_state)
        c.plastic_strain = std::max(c.plastic_strain, r.plastic_strain_change_relative());
      if (r.reaction_before > 0 && r.reaction_after > 0)
        c.reaction_jump = std::max(c.reaction_jump, r.reaction_jump_relative());
    }
  return c;
}

template <int dim>
nlohmann::json Simulation<dim>::ConversionExtremes::to_json() const {
  return {{"mass", mass},
          {"momentum", momentum},
          {"kinetic", kinetic},
          {"velocity_scale", velocity_scale},
          {"plastic_strain", plastic_strain},
          {"reaction_jump", reaction_jump},
          {"hole_mass", hole_mass}};
}

template <int dim>
void Simulation<dim>::ConversionExtremes::from_json(const nlohmann::json& j) {
  mass = j.value("mass", 0.0);
  momentum = j.value("momentum", 0.0);
  kinetic = j.value("kinetic", 0.0);
  velocity_scale = j.value("velocity_scale", 1.0);
  plastic_strain = j.value("plastic_strain", -1.0);
  reaction_jump = j.value("reaction_jump", -1.0);
  hole_mass = j.value("hole_mass", 0.0);
}

// The members defined here, not the nested struct: `template class Simulation<dim>` in
// simulation.cc may share a unity batch with this file, and instantiating the struct twice
// in one translation unit is an error.
template nlohmann::json Simulation<2>::ConversionExtremes::to_json() const;
template nlohmann::json Simulation<3>::ConversionExtremes::to_json() const;
template void Simulation<2>::ConversionExtremes::from_json(const nlohmann::json&);
template void Simulation<3>::ConversionExtremes::from_json(const nlohmann::json&);
template Simulation<2>::ConversionExtremes Simulation<2>::conversion_extremes() const;
template Simulation<3>::ConversionExtremes Simulation<3>::conversion_extremes() const;
template void Simulation<2>::record(unsigned int, double, RunContext&);
template void Simulation<3>::record(unsigned int, double, RunContext&);
template void Simulation<2>::write_output(unsigned int, double, RunContext&);
template void Simulation<3>::write_output(unsigned int, double, RunContext&);
template <int dim>
void Simulation<dim>::report_exact_error(RunContext& ctx) {
  exact_displacement_->set_time(last_recorded_time_);
  ErrorSums fem, particles;
  bool has_fem = false, has_particles = false;
  if (mechanics_) {
    fem = fem::displacement_error_sums(*mechanics_, *exact_displacement_);
    has_fem = mechanics_->n_active_cells() > 0;
  }
  if (coupled_) {
    const auto& p = coupled_->particles();
    const auto u = coupled_->physical_particle_displacements();
    // Free particles on their owners: ghosts are the FEM's, and particles fixed in every
    // component are prescribed. A particle fixed in some components only (a roller) counts
    // whole: its prescribed components add the boundary's own error, zero when the condition
    // is the exact field.
    particles = meshfree::displacement_error_sums(
        p, *exact_displacement_,
        [&](unsigned int i) {
          return coupled_->is_free(i) && coupled_->is_owned(i) && !p.is_fixed_in_every_component(i);
        },
        &u);
    has_particles = coupled_->n_free_particles() > 0;
  } else if (particles_) {
    // Not distributed: every rank holds the whole zone, rank 0's sums count once.
    // Distributed: each rank sums its owned particles (ghosts are fixed).
    const auto& p = particles_->particles();
    const auto u = particles_->physical_displacements();
    if (ctx.is_root() || particles_->distributed())
      particles = meshfree::displacement_error_sums(
          p, *exact_displacement_,
          [&](unsigned int i) {
            return particles_->is_owned(i) && !p.is_fixed_in_every_component(i);
          },
          &u);
    has_particles = true;
  }
  const auto sum = [&](ErrorSums e) {
    e.error_squared = dealii::Utilities::MPI::sum(e.error_squared, ctx.comm());
    e.reference_squared = dealii::Utilities::MPI::sum(e.reference_squared, ctx.comm());
    return e;
  };
  fem = sum(fem);
  particles = sum(particles);
  ErrorSums all = fem;
  all += particles;
  Summary& s = ctx.summary();
  s.set_figure("displacement_l2_error_relative", all.relative(), "-");
  if (has_fem && has_particles) {
    s.set_figure("fem_displacement_l2_error_relative", fem.relative(), "-");
    s.set_figure("particle_displacement_l2_error_relative", particles.relative(), "-");
  }
}

template void Simulation<2>::report_exact_error(RunContext&);
template void Simulation<3>::report_exact_error(RunContext&);
template void Simulation<2>::report_figures(RunContext&);
template void Simulation<3>::report_figures(RunContext&);

} // namespace spinesim::applications
