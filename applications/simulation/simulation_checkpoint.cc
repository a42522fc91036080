#include "applications/simulation/simulation_scenario.h"

#include "applications/framework/checkpoint_manifest.h"
#include "applications/framework/checkpoint_writer.h"
#include "applications/framework/root_decides.h"
#include "applications/framework/run_stops.h"
#include "base/exceptions.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

namespace spinesim::applications {

using namespace framework;

namespace fs = std::filesystem;

template <int dim>
nlohmann::json Simulation<dim>::pending_heat_sources(MPI_Comm comm) const {
  std::vector<std::string> ids;
  std::vector<double> values; // three per cell
  const auto at = [](const dealii::Vector<double>& v, unsigned int i) {
    return i < v.size() ? v(i) : 0.0;
  };
  for (const auto& cell : triangulation_->active_cell_iterators())
    if (cell->is_locally_owned()) {
      const unsigned int i = cell->active_cell_index();
      const double q[3] = {at(plastic_heating_, i), at(fracture_heating_, i),
                           at(particle_plastic_heating_, i)};
      if (q[0] != 0 || q[1] != 0 || q[2] != 0) {
        ids.push_back(cell->id().to_string());
        values.insert(values.end(), q, q + 3);
      }
    }
  const auto all_ids = dealii::Utilities::MPI::gather(comm, ids, 0);
  const auto all_values = dealii::Utilities::MPI::gather(comm, values, 0);
  nlohmann::json sources = nlohmann::json::array();
  for (std::size_t r = 0; r < all_ids.size(); ++r)
    for (std::size_t k = 0; k < all_ids[r].size(); ++k)
      sources.push_back({all_ids[r][k], all_values[r][3 * k], all_values[r][3 * k + 1],
                         all_values[r][3 * k + 2]});
  return sources;
}

template <int dim>
void Simulation<dim>::restore_pending_heat_sources(const nlohmann::json& sources) {
  std::map<std::string, std::array<double, 3>> by_cell;
  for (const auto& s : sources)
    by_cell[s.at(0).get<std::string>()] = {
        {s.at(1).get<double>(), s.at(2).get<double>(), s.at(3).get<double>()}};
  const unsigned int n = triangulation_->n_active_cells();
  plastic_heating_.reinit(n);
  fracture_heating_.reinit(n);
  particle_plastic_heating_.reinit(n);
  for (const auto& cell : triangulation_->active_cell_iterators())
    if (cell->is_locally_owned())
      if (const auto it = by_cell.find(cell->id().to_string()); it != by_cell.end()) {
        const unsigned int i = cell->active_cell_index();
        plastic_heating_(i) = it->second[0];
        fracture_heating_(i) = it->second[1];
        particle_plastic_heating_(i) = it->second[2];
      }
}

template <int dim>
void Simulation<dim>::write_checkpoint(unsigned int step, double time, RunContext& ctx) {
  // Order matters: deserialisation in load_checkpoint follows the same order.
  const auto write_parts = [&](const fs::path& staged) {
    const std::string mesh_file = (staged / "mesh").string();
    if (heat_)
      heat_->prepare_for_serialization();
    if (mechanics_)
      mechanics_->prepare_for_serialization(mesh_file);
    if (triangulation_)
      triangulation_->save(mesh_file);
    if (particles_ && (ctx.is_root() || particles_->distributed())) // distributed: a file per rank
      particles_->save((staged / "particles.bin").string());
    if (coupled_)
      coupled_->save((staged / "coupling.txt").string());
  };
  // The energy account's running sums (works, dissipations, conversions), summed over the
  // ranks: a restart continues them instead of starting the balance again (collective).
  std::vector<double> account_sums;
  if (sim_.energy_account && coupled_)
    account_sums = coupled_->energy_account_sums();
  else if (sim_.energy_account && mechanics_ && !quasi_static_) {
    const auto works = mechanics_->energy_account().works();
    account_sums.resize(works.size());
    dealii::Utilities::MPI::sum(works, ctx.comm(), account_sums);
  }
  // What the next heat step would have used: a restart continues as if never stopped.
  const nlohmann::json heat_sources =
      heat_ && triangulation_ ? pending_heat_sources(ctx.comm()) : nlohmann::json();
  const auto state = [&] {
    const nlohmann::json crack_json = crack_ ? crack_->to_json(ctx.comm()) : nlohmann::json();
    nlohmann::json state;
    state["step"] = step;
    state["time"] = time;
    state["output_cycle"] = output_cycle_;
    state["newton_iterations"] = newton_iterations_;
    state["linear_iterations"] = linear_iterations_;
    state["solution_pvd"] = solution_pvd_.to_json();
    state["temperature_pvd"] = temperature_pvd_.to_json();
    state["particles_pvd"] = particles_pvd_.to_json();
    state["final_step"] = sim_.steps;
    state["explicit_steps"] = explicit_steps_;
    // The coupled step only falls between conversions (bond breaks): recomputed at a restart
    // it could differ from the uninterrupted run's.
    state["coupled_time_step"] = coupled_dt_;
    state["peak_load"] = peak_load_;
    state["peak_load_time"] = peak_time_;
    state["last_load"] = last_load_;
    // The reference of Simulation/Minimum time step ratio and the initial energy of an initial
    // velocity field: a restarted run measures against the same values.
    state["first_stable_step"] = first_stable_step_;
    state["initial_kinetic_energy"] = initial_kinetic_energy_;
    if (!account_sums.empty())
      state["energy_account_sums"] = account_sums;
    state["relaxation_iterations"] = relaxation_iterations_;
    // The sub-step a cut left: the restarted run continues with it, as the uninterrupted one.
    state["relaxation_sub_step"] = relaxation_schedule_.sub_step;
    state["relaxation_sub_steps_converged"] = relaxation_schedule_.converged;
    state["relaxation_step_cuts"] = relaxation_step_cuts_;
    state["relaxation_breaking_passes"] = relaxation_breaking_passes_;
    state["relaxation_sub_steps"] = relaxation_sub_steps_;
    state["last_step_sub_steps"] = last_step_sub_steps_;
    if (particles_)
      state["particle_zone_step_cuts"] = particles_->step_cut_state();
    state["last_relaxation_iterations"] = last_relaxation_.iterations;
    state["last_relaxation_residual"] = last_relaxation_.relative_residual;
    state["conversion_extremes"] = conversion_extremes().to_json();
    if (crack_)
      state["crack_path"] = crack_json;
    if (heat_) {
      state["heat_supplied_energy"] = heat_->supplied_energy();
      state["initial_heat_content"] = initial_heat_content_;
      // The heat sources handed on to the next heat step and the plastic heat books.
      state["pending_heat_sources"] = heat_sources;
      state["fem_plastic_heat_applied"] = fem_plastic_heat_applied_;
      state["fem_plastic_heat_pending"] = fem_plastic_heat_pending_;
      if (coupled_) {
        state["particle_plastic_heat"] = coupled_->particle_plastic_heat();
        state["particle_plastic_heat_applied"] = particle_plastic_heat_applied_;
        state["particle_plastic_heat_pending"] = particle_plastic_heat_pending_;
        state["particle_plastic_heat_work"] = coupled_->particle_plastic_heat_work();
        state["fracture_heat_applied"] = fracture_heat_applied_;
      }
    }
    return state;
  };
  write_run_checkpoint(ctx, write_parts, state);
}

template <int dim>
unsigned int Simulation<dim>::load_checkpoint(RunContext& ctx) {
  const fs::path dir = ctx.checkpoint_dir();
  if (!fs::exists(dir / "state.json"))
    throw InvalidInput("--restart " + ctx.output().path().string(), "no checkpoint in this run",
                       "a run directory with checkpoint/state.json");
  // Sizes and hashes first: no reader below sees a truncated or altered file.
  root_decides(ctx.comm(), [&] {
    if (!verify_checkpoint_manifest(dir))
      ctx.log() << "  note: checkpoint without a manifest (an older run): not verified\n";
  });

  nlohmann::json state;
  try {
    std::ifstream in(dir / "state.json");
    state = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw InvalidInput((dir / "state.json").string(),
                       std::string("checkpoint state unreadable: ") + e.what(),
                       "the checkpoint as the run wrote it");
  }
  // The step counters decide what the restart does before any reader runs: a count of the
  // wrong type (which the JSON library throws as its own error) or sign is bad input here.
  const auto counter = [&](const char* key, unsigned int fallback) {
    if (!state.is_object())
      throw InvalidInput((dir / "state.json").string(), "checkpoint state is not a JSON object",
                         "the checkpoint as the run wrote it");
    if (!state.contains(key))
      return fallback;
    if (!state[key].is_number_unsigned() ||
        state[key].get<std::uint64_t>() > std::numeric_limits<unsigned int>::max())
      throw InvalidInput((dir / "state.json").string(),
                         std::string("checkpoint state malformed: \"") + key + "\" is " +
                             state[key].dump(),
                         "a step number >= 0, as the run wrote it");
    return state[key].get<unsigned int>();
  };
  const unsigned int step = counter("step", 0u);
  const unsigned int final_step = counter("final_step", sim_.steps);
  if (step >= sim_.steps && step >= final_step)
    throw NothingToRestart("the run in " + ctx.output().path().string() + " finished at step " +
                           std::to_string(step) + " of " + std::to_string(sim_.steps));
  if (sim_.stop_after_step > 0 && step >= sim_.stop_after_step)
    throw NothingToRestart(
        "the run in " + ctx.output().path().string() + " stopped at step " + std::to_string(step) +
        " as Simulation/Stop after step = " + std::to_string(sim_.stop_after_step) +
        " asks; continue with --set \"Simulation/Stop after step=0\" (or a "
        "later step)");

  // Readers that still fail (a checkpoint without a manifest) fail as bad input naming it.
  const std::string mesh_file = (dir / "mesh").string();
  try {
    if (triangulation_)
      triangulation_->load(mesh_file);
    if (particles_) {
      particles_->load((dir / "particles.bin").string());
      if (sim_.energy_account && !particles_->energy_account_restored())
        ctx.warn("Simulation/Energy account: the checkpoint was written without the particle "
                 "zone's account (or by an earlier version, which measured the stored energy of "
                 "NOSB-PD or SPG particles otherwise), so this run reports no balance figures "
                 "(NaN)");
    }
    if (heat_) {
      heat_->deserialize();
      heat_->set_time(state["time"].get<double>(), state.value("heat_supplied_energy", 0.0));
      initial_heat_content_ = state.value("initial_heat_content", 0.0);
    }
    if (effects_.thermal_expansion && heat_ && mechanics_)
      mechanics_->set_temperature_field(heat_->dof_handler(), heat_->solution(),
                                        sim_.reference_temperature);
    if (mechanics_)
      mechanics_->deserialize(mesh_file);
    if (coupled_) {
      coupled_->load((dir / "coupling.txt").string());
      if (heat_) {
        particle_plastic_heat_applied_ = state.value("particle_plastic_heat_applied", 0.0);
        particle_plastic_heat_pending_ = state.value("particle_plastic_heat_pending", 0.0);
        fracture_heat_applied_ = state.value("fracture_heat_applied", 0.0);
        coupled_->restore_plastic_heat(state.value("particle_plastic_heat", 0.0),
                                       state.value("particle_plastic_heat_work", 0.0));
      }
    }
    if (heat_) {
      fem_plastic_heat_applied_ = state.value("fem_plastic_heat_applied", 0.0);
      fem_plastic_heat_pending_ = state.value("fem_plastic_heat_pending", 0.0);
      if (triangulation_ && state.contains("pending_heat_sources"))
        restore_pending_heat_sources(state["pending_heat_sources"]);
    }
    if (sim_.energy_account && (coupled_ || (mechanics_ && !quasi_static_))) {
      if (state.contains("energy_account_sums")) {
        const auto sums = state["energy_account_sums"].get<std::vector<double>>();
        if (coupled_) {
          coupled_->restore_energy_account_sums(sums);
        } else {
          if (sums.size() != fem::ExplicitEnergy::n_works)
            throw InvalidInput(
                (dir / "state.json").string(),
                "energy_account_sums holds " + std::to_string(sums.size()) + " values",
                std::to_string(fem::ExplicitEnergy::n_works) + " for a run of the FEM alone");
          mechanics_->restore_energy_works(ctx.is_root() ? sums
                                                         : std::vector<double>(sums.size(), 0.0));
        }
      } else {
        ctx.warn("Simulation/Energy account starts again at the restart: the checkpoint was "
                 "written without the account's sums (an older run), so the balance figures "
                 "do not hold for a restarted run");
      }
    }
    explicit_steps_ = state.value("explicit_steps", 0u);
    coupled_dt_ = state.value("coupled_time_step", 0.0); // 0: recomputed (older checkpoints)
    peak_load_ = state.value("peak_load", 0.0);
    peak_time_ = state.value("peak_load_time", 0.0);
    last_load_ = state.value("last_load", 0.0);
    first_stable_step_ = state.value("first_stable_step", 0.0);
    initial_kinetic_energy_ = state.value("initial_kinetic_energy", 0.0);
    relaxation_iterations_ = state.value("relaxation_iterations", 0ul);
    relaxation_schedule_.sub_step = state.value("relaxation_sub_step", 0.0);
    relaxation_schedule_.converged = state.value("relaxation_sub_steps_converged", 0u);
    relaxation_step_cuts_ = state.value("relaxation_step_cuts", 0ul);
    relaxation_breaking_passes_ = state.value("relaxation_breaking_passes", 0ul);
    relaxation_sub_steps_ = state.value("relaxation_sub_steps", 0ul);
    last_step_sub_steps_ = state.value("last_step_sub_steps", 0u);
    if (particles_ && state.contains("particle_zone_step_cuts"))
      particles_->restore_step_cut_state(
          state["particle_zone_step_cuts"].get<std::array<double, 3>>());
    last_relaxation_.iterations = state.value("last_relaxation_iterations", 0u);
    last_relaxation_.relative_residual = state.value("last_relaxation_residual", 0.0);
    if (state.contains("conversion_extremes"))
      restored_conversion_extremes_.from_json(state["conversion_extremes"]);
    if (crack_ && state.contains("crack_path"))
      crack_->from_json(state["crack_path"]);
    output_cycle_ = state["output_cycle"];
    newton_iterations_ = state["newton_iterations"];
    linear_iterations_ = state["linear_iterations"];
    solution_pvd_.from_json(state["solution_pvd"]);
    temperature_pvd_.from_json(state["temperature_pvd"]);
    particles_pvd_.from_json(state["particles_pvd"]);
  } catch (const InvalidInput&) {
    throw;
  } catch (const std::exception& e) {
    throw InvalidInput(dir.string(), std::string("checkpoint unreadable: ") + e.what(),
                       "the checkpoint as the run wrote it");
  }
  const double time = state["time"];
  // Rows written after the checkpoint came from a segment that did not survive.
  root_decides(ctx.comm(), [&] {
    ctx.history().load(dir / "history.csv");
    ctx.history().truncate_after("time", time * (1 + 1e-12));
  });
  // A checkpoint written inside step + 1 (an interrupt between its explicit sub-steps) holds
  // a time past step's.
  if (time > step * (sim_.end_time / sim_.steps) * (1 + 1e-9))
    ctx.log() << "  restarting inside step " << step + 1 << ", at t = " << time << " s\n";
  else
    ctx.log() << "  restarting after step " << step << ", t = " << time << " s\n";
  return step;
}

template void Simulation<2>::write_checkpoint(unsigned int, double, RunContext&);
template void Simulation<3>::write_checkpoint(unsigned int, double, RunContext&);
template unsigned int Simulation<2>::load_checkpoint(RunContext&);
template unsigned int Simulation<3>::load_checkpoint(RunContext&);

} // namespace spinesim::applications
