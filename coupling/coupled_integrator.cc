#include "coupling/coupled_integrator.h"

#include "base/collective_failure.h"
#include "base/exceptions.h"
#include "fem/heat/heat_solver.h"

#include <deal.II/base/array_view.h>
#include <deal.II/base/mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>

namespace spinesim::coupling {

std::string RelaxationProgress::describe(const char* force_unit) const {
  std::ostringstream s;
  s << "relaxation pseudo-step " << iteration << ", relative residual " << relative_residual << " ("
    << residual << force_unit << " of " << reaction << force_unit << " reactions), damping "
    << damping << " 1/s, stiffness estimate " << stiffness_estimate << " 1/s^2, " << free_particles
    << " free particles, " << converted_cells << " cells converted so far, " << seconds << " s";
  return s.str();
}

using namespace dealii;

template <int dim>
double CoupledIntegrator<dim>::stable_time_step() const {
  const auto& particles = state_.particles;
  const MPI_Comm comm = state_.fem.mpi_communicator(); // rows live with their owners
  stiffness_bound_.clear();
  if (state_.n_free_particles() > 0) {
    stiffness_bound_ = state_.method->stiffness_bound(particles, state_.bonds);
    joint_.contact().add_stiffness_bound(stiffness_bound_);
  }
  refresh_contact_bound();
  particle_step_ = Utilities::MPI::min(particle_step(), comm);
  return combined_step(state_.fem.stable_time_step(), particle_step_);
}

template <int dim>
double CoupledIntegrator<dim>::stable_time_step_fem_refreshed() const {
  if (!(particle_step_ > 0))
    return stable_time_step();
  const bool contacts = has_short_range_forces();
  if (contacts)
    refresh_contact_bound();
  if (contacts || state_.fem.parameters().kinematics != "small_strain")
    particle_step_ = Utilities::MPI::min(particle_step(), state_.fem.mpi_communicator());
  return combined_step(state_.fem.stable_time_step(), particle_step_);
}

template <int dim>
void CoupledIntegrator<dim>::restore_stiffness_bound(std::vector<double> bound) {
  stiffness_bound_ = std::move(bound);
  refresh_contact_bound();
  particle_step_ = stiffness_bound_.empty()
                       ? -1
                       : Utilities::MPI::min(particle_step(), state_.fem.mpi_communicator());
}

template <int dim>
double CoupledIntegrator<dim>::own_particle_step(unsigned int i) const {
  const auto& particles = state_.particles;
  const double inf = std::numeric_limits<double>::infinity();
  // Owned rows only: another rank's particle holds a partial row sum here (the neighbour
  // families this rank keeps), never more than its owner's, so the minimum over the ranks
  // is the owners' either way, and a checkpoint need keep the owners' entries alone.
  if (i >= stiffness_bound_.size() || !state_.free[i] || !state_.is_owned(i) ||
      !(stiffness_bound_[i] > 0))
    return inf;
  const double bound = stiffness_bound_[i] + (i < contact_bound_.size() ? contact_bound_[i] : 0.0);
  // Under finite strain a compressed family is stiffer in its reference coordinates: a
  // bond shortened to λ of its length stiffens like a cell edge shortened to λ (the FEM's
  // step of the current cells), so the bound grows by 1/λ² with the family's shortest
  // stretch (Belytschko, Liu & Moran 2000, §6.3: the step scales with the current element
  // size).
  double stretch = 1;
  if (state_.fem.parameters().kinematics != "small_strain")
    for (std::size_t k = state_.bonds.begin(i); k < state_.bonds.end(i); ++k) {
      if (state_.bonds.broken[k]) // no force: fragments may close up freely
        continue;
      const unsigned int j = state_.bonds.neighbor[k];
      const auto xi = particles.reference_position(j) - particles.reference_position(i);
      const auto eta = particles.displacement(j) - particles.displacement(i);
      stretch = std::min(stretch, (xi + eta).norm() / xi.norm());
    }
  return state_.prm.time_step_safety * stretch * std::sqrt(2.0 * particles.density(i) / bound);
}

template <int dim>
double CoupledIntegrator<dim>::particle_step() const {
  double dt_pd = std::numeric_limits<double>::infinity();
  for (unsigned int i = 0; i < stiffness_bound_.size(); ++i)
    dt_pd = std::min(dt_pd, own_particle_step(i));
  return dt_pd;
}

template <int dim>
double CoupledIntegrator<dim>::relaxation_time_step() {
  const double dt = stable_time_step(); // also renews the particles' stiffness bound
  relax_mass_scale_.clear();
  state_.fem.clear_relaxation_masses();
  // The energy splice's step bound and its mass-weighted correction are those of the real
  // masses: it relaxes with them.
  if (state_.fem.parameters().relaxation_masses != "scaled" || splice_.on())
    return dt;
  // Fictitious masses (Underwood 1983; Kilic & Madenci 2010 for PD): each part stable by itself
  // at the reference step; a cell or particle with a longer own step moves with a lighter mass,
  // one with a shorter step (particles finer than the cells) with a heavier one. The
  // equilibrium is the same; the pseudo-dynamics reach it in fewer steps.
  const bool cells = state_.fem.n_active_cells() > 0;
  const double reference = cells ? state_.fem.stable_time_step() : particle_step_;
  if (!(reference > 0) || !std::isfinite(reference))
    return dt;
  if (cells)
    state_.fem.set_relaxation_masses(reference);
  relax_mass_scale_.assign(state_.particles.size(), 1.0);
  for (unsigned int i = 0; i < state_.particles.size(); ++i) {
    const double own = own_particle_step(i);
    if (std::isfinite(own) && own > 0)
      relax_mass_scale_[i] = (reference / own) * (reference / own);
  }
  return reference;
}

template <int dim>
double CoupledIntegrator<dim>::combined_step(double dt_fem, double dt_pd) const {
  if (!(splice_.on() && state_.n_free_particles() > 0))
    return std::min(dt_fem, dt_pd);
  // The energy splice adds the two models' stiffnesses where they overlap (the ghost band
  // counts in both) and passes the FEM's interface stiffness to the particles: by Weyl's
  // inequality the coupled ω_max² is at most the sum of the parts' ω², ω = 2 / Δt for each
  // part's safe step, plus the correction's.
  // The interface DoFs have no inertia: their stiffness acts on the particles of their fits,
  // which can raise the FEM's share of ω² by interface_mass_ratio() where fits extrapolate (a
  // jagged interface after conversions; without it a 3-D bar converting 1000 cells blew up).
  const double fem_share = std::max(1.0, splice_.interface_mass_ratio());
  return splice_.limit_step(1.0 / std::sqrt(fem_share / (dt_fem * dt_fem) + 1.0 / (dt_pd * dt_pd)));
}

template <int dim>
bool CoupledIntegrator<dim>::bonds_broke_in_last_step() const {
  return Utilities::MPI::logical_or(broken_last_step_ > 0, state_.fem.mpi_communicator());
}

template <int dim>
void CoupledIntegrator<dim>::refresh_contact_bound() const {
  contact_bound_.clear();
  if (!has_short_range_forces() || state_.n_free_particles() == 0)
    return;
  contact_bound_.assign(state_.particles.size(), 0.0);
  state_.method->add_contact_bound(state_.particles, state_.bonds, contact_bound_);
}

template <int dim>
void CoupledIntegrator<dim>::step(double dt) {
  broken_last_step_ = 0;
  advance(dt, state_.fem.parameters().mass_damping, time_ + dt, false, nullptr);
  time_ += dt;
  check_particle_speeds();
  // Cracks make the splice's correction (made for the intact material) inexact; where one cuts
  // the body next to the interface the stored energy can turn indefinite and a mode grows
  // while the energy stays conserved. Checked every 10 steps once bonds are broken (a
  // collective check; such a mode took about 30 steps per e-fold where it was seen).
  if (!splice_.on() || state_.n_free_particles() == 0 || ++steps_since_splice_check_ < 10)
    return;
  check_splice_energy();
}

template <int dim>
void CoupledIntegrator<dim>::check_splice_energy() {
  if (!splice_.on() || state_.n_free_particles() == 0)
    return;
  steps_since_splice_check_ = 0;
  if (!any_broken_)
    any_broken_ = std::find(state_.bonds.broken.begin(), state_.bonds.broken.end(),
                            std::uint8_t(1)) != state_.bonds.broken.end();
  if (Utilities::MPI::logical_or(any_broken_, state_.fem.mpi_communicator()))
    splice_.check_stored_energy();
}

template <int dim>
void CoupledIntegrator<dim>::check_particle_speeds() const {
  // The material points of a solid do not outrun its P wave (no shocks are modelled): a free
  // particle faster than c_p = sqrt(M / rho), M = E (1 - nu) / ((1 + nu)(1 - 2 nu)) the
  // constrained modulus (the fastest wave of any plane model), means the run diverged. Energy
  // fed in at an interface grows for hundreds of steps before anything becomes NaN.
  // Each particle against its own law's wave speed (the method's default law where the table
  // has none: a law that cannot describe itself).
  const auto& laws = *state_.laws;
  const double E = state_.youngs, nu = state_.poisson, rho = state_.density;
  const double c2_default = E > 0 && rho > 0 && nu < 0.5
                                ? E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho
                                : std::numeric_limits<double>::infinity();
  const auto& p = state_.particles;
  for (unsigned int i = 0; i < p.size(); ++i) {
    if (!state_.free[i] || !state_.is_owned(i))
      continue;
    const unsigned int m = p.material_id(i);
    const double c2 = m < laws.size() ? laws[m].p_wave_speed * laws[m].p_wave_speed : c2_default;
    if (!(p.velocity(i).norm_square() <= c2)) {
      std::ostringstream what, where;
      what << "particle speed " << p.velocity(i).norm() << " m/s exceeds the P-wave speed "
           << std::sqrt(c2) << " m/s (diverged)";
      where << "particle " << i << " at (" << p.reference_position(i) << ")";
      throw NumericalFailure(what.str(), where.str(),
                             "either the body was set moving at or above the P-wave speed "
                             "(Simulation/Initial velocity; the solids here carry no shock "
                             "waves), or energy grew without bound. Where a crack or fragments "
                             "reach the "
                             "FEM/particle interface: widen the conversion region and Coupling/"
                             "Buffer so the crack stays inside the particles. In a long run "
                             "without that, with Coupling/Splice = overlap: that splice is not "
                             "energy-conserving and some of its modes grow slowly (a smaller "
                             "time step does not cure it); Coupling/Splice = energy conserves "
                             "energy (docs/coupling.md, the energy splice)");
    }
  }
}

template <int dim>
std::size_t CoupledIntegrator<dim>::share_bond_breaks() {
  // A method whose breaks reshape its neighbours' rows (SPG) must break a pair on every rank
  // holding a row of either end; the owner of a free particle decides (it holds the rows of
  // the particle and all its partners), the others follow before the next force pass.
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (!state_.prm.damage || !state_.method->shares_bond_breaks() ||
      Utilities::MPI::n_mpi_processes(comm) == 1) {
    if (state_.prm.damage && state_.method->shares_bond_breaks())
      state_.method->take_broken_pairs(); // one rank holds every row already
    return 0;
  }
  std::vector<std::pair<unsigned int, unsigned int>> all;
  for (const auto& part : Utilities::MPI::all_gather(comm, state_.method->take_broken_pairs()))
    all.insert(all.end(), part.begin(), part.end());
  if (!all.empty())
    state_.method->break_pairs(state_.particles, state_.bonds, all);
  return all.size();
}

template <int dim>
bool CoupledIntegrator<dim>::break_at_equilibrium() {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  std::size_t broke = 0, shared = 0;
  // Every rank holds the same particle records (their count decides alike on all ranks).
  if (state_.n_free_particles() > 0) {
    fracture_.before_forces();
    std::exception_ptr failure;
    try {
      broke = state_.method->compute_forces(state_.particles, state_.bonds, true);
    } catch (...) {
      failure = std::current_exception();
    }
    raise_on_every_rank(failure, comm);
    fracture_.after_forces(broke);
    shared = share_bond_breaks();
    broken_last_step_ = broke;
  }
  return Utilities::MPI::sum(broke, comm) + shared > 0;
}

template <int dim>
void CoupledIntegrator<dim>::advance(double dt, double a, double load_time, bool first,
                                     RelaxationSums* sums) {
  // Central differences on both sides, all forces from the state at t_n:
  // 1. PD forces on free particles (ghosts hold the FEM field of t_n); particles to t_{n+1}.
  // 2. Interface DoFs of t_{n+1} from the particles; FEM step from t_n to t_{n+1}.
  // 3. Ghosts to the FEM field of t_{n+1}.
  // A relaxation step (sums given) holds the loads at load_time and adds this rank's sums of
  // the free particles to the FEM's.
  auto& particles = state_.particles;
  // The velocity interval of this step (steps change where a run lands on its output times):
  // the FEM's, so both models advance their velocities alike; relaxation keeps one pseudo-step.
  const double h = sums ? dt : state_.fem.velocity_interval(dt);
  if (state_.n_free_particles() > 0) {
    // With heat, bonds breaking in this force pass release their energy (at the state of t_n)
    // into their particle's heat account.
    fracture_.before_forces();
    if (!sums)
      energy_.before_forces();
    if (!sums && energy_.on() && state_.prm.damage && state_.method->forces_derive_from_energy()) {
      // The forces before this pass's breaks, for the work the breaks take out of the motion
      // (ParticleEnergy::after_forces): one pass more per step while the account is on. Only
      // where the forces derive from the booked energy (else the term has no meaning).
      state_.method->compute_forces_before_breaks(particles, state_.bonds);
      energy_.record_forces_before_breaks();
    }
    const auto start = std::chrono::steady_clock::now();
    // A law that fails at one particle (a return mapping that does not converge, det F ≤ 0)
    // fails on every rank before the next exchange, so no rank waits there and a relaxation
    // can undo the attempt (relax(), FemParticleCoupling::relax_step).
    std::exception_ptr failure;
    try {
      // Coupling/Break bonds = at equilibrium: a relaxation's pseudo-steps break nothing
      // (relax() breaks at its equilibria).
      const bool breaking =
          state_.prm.damage && !(sums && state_.prm.relaxation_breaks_at_equilibrium);
      broken_last_step_ = state_.method->compute_forces(particles, state_.bonds, breaking);
    } catch (...) {
      failure = std::current_exception();
    }
    raise_on_every_rank(failure, state_.fem.mpi_communicator());
    particle_force_seconds_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (unsigned int i = 0; i < particles.size(); ++i)
      particle_updates_ += state_.free[i] && state_.is_owned(i);
    fracture_.after_forces(broken_last_step_);
    share_bond_breaks();
    if (joint_.on())
      joint_.take_particle_forces(); // at the same state as the FEM's forces below
    if (!sums)
      energy_.after_forces(); // the stored energy the breaks of this pass released
    // Explicit steps commit the material history every step, as the FEM does; a relaxation
    // commits both models once, at equilibrium (relax()), so the pseudo-dynamics leave no
    // plastic trace (MechanicsSolver::relaxation_step).
    if (!sums) {
      state_.method->commit_state();
      joint_.contact().commit();
    }
    auto& previous = relax_acceleration_;
    if (sums && (first || previous.size() != dim * particles.size()))
      previous.assign(dim * particles.size(), std::numeric_limits<double>::quiet_NaN());
  }
  // The particle update to t_{n+1}. The overlap splice makes it now; the energy splice inside
  // the FEM's force hook, once the FEM's forces on the interface DoFs of t_n are known.
  const bool energy_splice = splice_.on() && state_.n_free_particles() > 0;
  if (energy_splice)
    splice_.take_particle_forces();
  bool moved = false;
  const auto move_particles = [&](bool with_splice) {
    moved = true;
    const auto* extra = with_splice ? &splice_.splice_forces() : nullptr;
    const auto force_on = [&](unsigned int i, unsigned int d) {
      return particles.force(i)[d] + particles.external_force(i)[d] +
             (extra ? (*extra)[i][d] : 0.0);
    };
    auto& previous = relax_acceleration_;
    // The damped central-difference update of one component, in both loops below.
    const DampedCentralDifference step(h, dt, a);
    const auto advance_component = [&](unsigned int i, unsigned int d, double acc) {
      step.advance(particles.velocity(i)[d], particles.displacement(i)[d], acc);
    };
    if (!sums) {
      // Independent particles: the threads share them (the relaxation sums below keep one
      // thread and a fixed order).
      const long n = static_cast<long>(particles.size());
      // A few flops a particle: worth a parallel region from a couple of thousand on.
#pragma omp parallel for schedule(static) if (n > 2000)
      for (long ii = 0; ii < n; ++ii) {
        const unsigned int i = static_cast<unsigned int>(ii);
        if (!state_.free[i] || !state_.is_owned(i))
          continue;
        const double m = particles.mass(i);
        for (unsigned int d = 0; d < dim; ++d) {
          if (particles.is_fixed(i, d))
            continue;
          advance_component(i, d, force_on(i, d) / m);
        }
      }
    }
    for (unsigned int i = 0; sums && i < particles.size(); ++i) {
      if (!state_.free[i] || !state_.is_owned(i))
        continue;
      const double m =
          particles.mass(i) * (i < relax_mass_scale_.size() ? relax_mass_scale_[i] : 1.0);
      for (unsigned int d = 0; d < dim; ++d) {
        const double f = force_on(i, d);
        if (particles.is_fixed(i, d)) {
          sums->reaction_square += f * f;
          continue;
        }
        const double acc = f / m;
        sums->add_free(f, acc, previous[dim * i + d], particles.displacement(i)[d],
                       particles.velocity(i)[d], dt);
        advance_component(i, d, acc);
      }
    }
    boundary_.apply(load_time, dt);
    if (!sums)
      energy_.after_update(time_, dt, h, a);
    halo_.exchange(); // partners and interface stencils at t_{n+1}
    interface_.update();
  };
  if (state_.n_free_particles() > 0 && !energy_splice)
    move_particles(false);
  if (!sums && state_.n_free_particles() == 0)
    energy_.after_update(time_, dt, h, a); // no particles (yet): their share is zero
  {
    // The hook lives for this step only (also when the step throws).
    struct HookGuard {
      fem::MechanicsSolver<dim>& fem;
      ~HookGuard() { fem.set_step_force_hook({}); }
    } guard{state_.fem};
    if (energy_splice)
      state_.fem.set_step_force_hook(
          [&](const typename fem::MechanicsSolver<dim>::StepForces& forces) {
            splice_.on_fem_forces(forces);
            move_particles(true);
          });
    else if (joint_.on() && joint_.n_targets() > 0 && state_.n_free_particles() > 0)
      state_.fem.set_step_force_hook(
          [&](const typename fem::MechanicsSolver<dim>::StepForces& forces) {
            joint_.add_reactions(forces);
          });
    if (sums) {
      *sums += state_.fem.relaxation_step(dt, a, load_time, first);
    } else {
      state_.fem.explicit_step(dt);
    }
  }
  if (energy_splice && !moved)
    move_particles(false); // every cell converted: the FEM step had no forces to hand over
  if (state_.n_ghost_particles() > 0)
    ghosts_.update();
  // The FEM temperature drives the particles' temperatures (synchronise() spreads them); it
  // holds still while a relaxation runs, so its first pseudo-step reads it.
  if (state_.heat && particles.size() > 0 && (!sums || first))
    ghosts_.update_temperatures();
}

template <int dim>
RelaxationReport<dim>
CoupledIntegrator<dim>::relax(double time, bool with_conversion,
                              const std::function<void(const RelaxationProgress&)>& progress) {
  // Adaptive dynamic relaxation of the coupled system at the load of `time` (Underwood 1983;
  // Kilic & Madenci 2010 for PD; base/dynamic_relaxation.h): central differences in
  // pseudo-time with the relaxation masses (relaxation_time_step(): scaled, or the real lumped
  // and particle masses with Mechanics/Relaxation masses = lumped or the energy splice), and the
  // damping c = 2 sqrt(uᵀ k u / uᵀ u) from the local stiffness estimates of both models
  // (critical for the lowest mode, updated every step, one step late). Converged when ‖free
  // residual‖ ≤ tolerance × max(‖reactions‖, largest ‖free residual‖ of this relaxation). Bonds
  // break as the state relaxes (or, with Coupling/Break bonds = at equilibrium, at each
  // equilibrium, and the state relaxes again at the same load while any breaks); cells convert
  // at equilibrium, and the state relaxes again after a conversion. Velocities are
  // pseudo-velocities and end at zero.
  const MPI_Comm comm = state_.fem.mpi_communicator();
  RelaxationReport<dim> report;
  // The real masses come back however the relaxation ends.
  struct MassGuard {
    CoupledIntegrator& integrator;
    ~MassGuard() {
      integrator.relax_mass_scale_.clear();
      integrator.state_.fem.clear_relaxation_masses();
    }
  } guard{*this};
  const auto started = std::chrono::steady_clock::now();
  double dt = relaxation_time_step();
  double c = 0, peak_residual = 0;
  bool first = true;
  time_ = time; // held: advance() with sums does not move the clock
  // A failure raised on every rank at once ends the attempt with its report (the caller may
  // undo it and cut the step); the state is then that of the failed pseudo-step.
  const auto failed = [&](unsigned int it, const NumericalFailure& e) {
    report.iterations = it;
    report.converged = false;
    report.failure = e.what_failed() + " (" + e.location() + ")";
    report.failure_hint = e.hint();
    return report;
  };
  // Each relaxation after bonds broke at an equilibrium has Relaxation max iterations of its own
  // (pass_start: its first pseudo-step − 1); a conversion's shares the step's.
  unsigned int pass_start = 0;
  for (unsigned int it = 1; it - pass_start <= state_.prm.relaxation_max_iterations; ++it) {
    RelaxationSums local;
    try {
      advance(dt, c, time, first, &local);
    } catch (const NumericalFailure& e) {
      if (!e.collective() && Utilities::MPI::n_mpi_processes(comm) > 1)
        throw; // one rank alone: the others cannot follow an undo
      return failed(it, e);
    }
    first = false;
    double values[4] = {local.stiffness_numerator, local.stiffness_denominator,
                        local.residual_square, local.reaction_square};
    Utilities::MPI::sum(ArrayView<const double>(values, 4), comm, ArrayView<double>(values, 4));
    RelaxationSums sums;
    sums.stiffness_numerator = values[0];
    sums.stiffness_denominator = values[1];
    sums.residual_square = values[2];
    sums.reaction_square = values[3];
    const double residual = std::sqrt(sums.residual_square);
    const double reaction = std::sqrt(sums.reaction_square);
    peak_residual = std::max(peak_residual, residual);
    const double scale = std::max(reaction, peak_residual);
    report.iterations = it;
    report.relative_residual = scale > 0 ? residual / scale : 0.0;
    if (!std::isfinite(residual)) // the sums are every rank's: a collective failure
      return failed(it, NumericalFailure("non-finite residual",
                                         "relaxation at t = " + significant(time, 6) +
                                             " s, pseudo-step " + std::to_string(it),
                                         "check the materials and the loads of this step"));
    // The first step's forces are those of the previous state: judge from the second on.
    if (it > pass_start + 1 && residual <= state_.prm.relaxation_tolerance * scale) {
      // Bonds that the equilibrium stretches past their criterion break, and the state relaxes
      // again from rest at the same load (from the same committed histories: the step's trial
      // state is committed once, at the equilibrium where nothing more breaks).
      if (state_.prm.damage && state_.prm.relaxation_breaks_at_equilibrium) {
        bool broke = false;
        try {
          broke = break_at_equilibrium();
        } catch (const NumericalFailure& e) {
          if (!e.collective() && Utilities::MPI::n_mpi_processes(comm) > 1)
            throw;
          return failed(it, e);
        }
        if (broke) {
          if (++report.breaking_passes >= state_.prm.relaxation_breaking_passes) {
            report.still_breaking = true;
            break;
          }
          for (unsigned int i = 0; i < state_.particles.size(); ++i)
            state_.particles.velocity(i) = Tensor<1, dim>();
          state_.fem.clear_velocity();
          pass_start = it;
          first = true; // softer: restart the stiffness estimate
          c = 0;
          continue;
        }
      }
      // Equilibrium: the trial histories of both models are the step's result.
      state_.fem.commit_relaxation();
      if (state_.method)
        state_.method->commit_state();
      joint_.contact().commit(); // friction's stick points, like the material history
      // Conversion is decided at equilibrium, not on the transient strains of the relaxation
      // (which depend on its path and tolerance): cells flagged now convert and the state
      // relaxes again, until no cell converts.
      // The reactions at this equilibrium close the previous conversion's jump measure (same
      // load, before and after the cells turned into particles).
      if (!report.conversions.empty()) {
        report.conversions.back().reaction_after = reaction;
        converter_.last_report().reaction_after = reaction;
      }
      auto r = with_conversion ? converter_.convert_flagged() : ConversionReport<dim>();
      if (r.cells == 0) {
        report.converged = true;
        break;
      }
      r.reaction_before = converter_.last_report().reaction_before = reaction;
      report.conversions.push_back(r);
      dt = relaxation_time_step();
      first = true; // new unknowns: restart the stiffness estimate
      c = 0;
      continue;
    }
    // A short-range pair engaged that the masses' bound did not count: renew them before the
    // pseudo-dynamics outrun it (and restart the stiffness estimate, as after a conversion).
    if (has_short_range_forces() &&
        Utilities::MPI::logical_or(state_.method->stiffness_bound_stale(), comm)) {
      dt = relaxation_time_step();
      first = true;
      c = 0;
      continue;
    }
    c = sums.damping(dt);
    report.damping = c;
    if (progress && state_.prm.relaxation_report_interval > 0 &&
        it % state_.prm.relaxation_report_interval == 0) {
      RelaxationProgress p;
      p.iteration = it;
      p.relative_residual = report.relative_residual;
      p.residual = residual;
      p.reaction = reaction;
      p.damping = c;
      p.stiffness_estimate = sums.stiffness_denominator > 0
                                 ? sums.stiffness_numerator / sums.stiffness_denominator
                                 : 0.0;
      unsigned int owned_free = 0; // every rank holds every record: count each once
      for (unsigned int i = 0; i < state_.particles.size(); ++i)
        owned_free += state_.free[i] && state_.is_owned(i);
      p.free_particles = Utilities::MPI::sum(owned_free, comm);
      for (const auto& r : report.conversions)
        p.converted_cells += r.cells;
      p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      progress(p);
    }
  }
  // Quasi-static: the pseudo-velocities go.
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    state_.particles.velocity(i) = Tensor<1, dim>();
  state_.fem.clear_velocity();
  if (state_.n_ghost_particles() > 0)
    ghosts_.update();
  return report;
}

template class CoupledIntegrator<2>;
template class CoupledIntegrator<3>;

} // namespace spinesim::coupling
