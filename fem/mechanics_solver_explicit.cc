// Explicit dynamics of MechanicsSolver: the CFL-limited step, central differences with the
// lumped mass, and the dynamic-relaxation step whose sums drive adaptive damping.

#include "fem/mechanics_solver.h"

#include "base/collective_failure.h"
#include "base/dynamic_relaxation.h"
#include "base/exceptions.h"
#include "base/scoped_time.h"
#include "fem/sparse_product.h"

#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace spinesim::fem {

using namespace dealii;

template <int dim>
double MechanicsSolver<dim>::cell_step(const typename DoFHandler<dim>::active_cell_iterator& cell,
                                       bool current, std::vector<Point<dim>>& x) const {
  // The shortest distance between two vertices (not the diameter) bounds the highest mode of
  // distorted cells; degree p splits the edge into p node spacings.
  double shortest = cell->minimum_vertex_distance();
  if (current) {
    for (const unsigned int v : cell->vertex_indices()) {
      x[v] = cell->vertex(v);
      for (unsigned int c = 0; c < dim; ++c)
        x[v][c] += u_ghost_(cell->vertex_dof_index(v, c));
    }
    shortest = std::numeric_limits<double>::max();
    for (unsigned int a = 0; a < x.size(); ++a)
      for (unsigned int b = a + 1; b < x.size(); ++b)
        shortest = std::min(shortest, x[a].distance(x[b]));
  }
  const double h = shortest / prm_.fe_degree;
  const auto& law = cell_material(cell);
  // Plane stress carries the in-plane P wave sqrt(E / ((1 − ν²) ρ)), slower than the 3-D one.
  const double c =
      prm_.plane_stress
          ? std::sqrt(law.youngs_modulus() /
                      ((1 - law.poisson_ratio() * law.poisson_ratio()) * law.density()))
          : law.p_wave_speed();
  return h / c;
}

template <int dim>
double MechanicsSolver<dim>::stable_time_step(Point<dim>* where) const {
  double dt = std::numeric_limits<double>::max();
  Point<dim> centre; // of the cell that sets the step (deformed under finite strain)
  // Finite strain: the cells as they are now (an impact can shorten them several times).
  const bool current = prm_.kinematics == "finite_strain";
  std::vector<Point<dim>> x(GeometryInfo<dim>::vertices_per_cell);
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      const double step = cell_step(cell, current, x); // x: the current vertices
      if (step < dt) {
        dt = step;
        if (where) {
          centre = Point<dim>();
          for (const unsigned int v : cell->vertex_indices())
            centre += (current ? x[v] : cell->vertex(v)) / double(cell->n_vertices());
        }
      }
    }
  if (where) {
    const auto m = Utilities::MPI::min_max_avg(dt, comm_);
    *where = Utilities::MPI::broadcast(comm_, centre, m.min_index);
    return prm_.cfl_safety_factor * m.min;
  }
  return prm_.cfl_safety_factor * Utilities::MPI::min(dt, comm_);
}

template <int dim>
void MechanicsSolver<dim>::explicit_step(double dt) {
  if (!is_setup_)
    setup();
  if (n_active_cells() == 0) {
    // Every cell converted: the FEM has no unknowns left, its step only advances time.
    raw_residual_ = 0;
    rhs_ = 0;
    if (energy_account_on_) { // nothing moves: the works stay, the energies are zero
      energy_.time = time_;
      energy_.external.add(0, 0);
      energy_.interface.add(0, 0);
      energy_.damping.add(0, 0);
      energy_.internal.add(0, 0);
      energy_.kinetic = energy_.kinetic_central = energy_.strain = 0;
      energy_.valid = true;
    }
    time_ += dt;
    previous_step_ = dt;
    return;
  }
  target_time_ = time_;
  central_difference(dt, prm_.mass_damping, time_ + dt, nullptr);
  if (!states_stale_)
    commit_history();
  time_ += dt;
  previous_step_ = dt;
  update_ghosts();
}

template <int dim>
typename MechanicsSolver<dim>::RelaxationSums
MechanicsSolver<dim>::relaxation_step(double dt, double damping, double time, bool first) {
  if (!is_setup_)
    setup();
  RelaxationSums sums;
  time_ = previous_time_ = target_time_ = time;
  if (n_active_cells() == 0) {
    raw_residual_ = 0;
    rhs_ = 0;
    return sums;
  }
  if (first)
    relax_acceleration_.clear();
  central_difference(dt, damping, time, &sums);
  update_ghosts();
  return sums;
}

template <int dim>
void MechanicsSolver<dim>::commit_relaxation() {
  if (!states_stale_)
    commit_history();
}

template <int dim>
void MechanicsSolver<dim>::clear_velocity() {
  v_ = 0;
  previous_step_ = -1; // at rest: the next step starts as the first
  update_ghosts();
}

template <int dim>
unsigned int MechanicsSolver<dim>::relax_quasi_static(double time, double tolerance,
                                                      unsigned int max_steps) {
  if (!is_setup_)
    setup();
  const double dt = stable_time_step();
  double c = 0, peak_residual = 0, relative = 0;
  v_ = 0;
  update_ghosts();
  trial_ = committed_;
  // The real masses come back however the relaxation ends.
  struct MassGuard {
    MechanicsSolver& solver;
    ~MassGuard() { solver.clear_relaxation_masses(); }
  } guard{*this};
  if (prm_.relaxation_masses == "scaled")
    set_relaxation_masses(dt);
  for (unsigned int it = 1; it <= max_steps; ++it) {
    const RelaxationSums local = relaxation_step(dt, c, time, it == 1);
    double v[4] = {local.stiffness_numerator, local.stiffness_denominator, local.residual_square,
                   local.reaction_square};
    Utilities::MPI::sum(ArrayView<const double>(v, 4), comm_, ArrayView<double>(v, 4));
    RelaxationSums sums;
    sums.stiffness_numerator = v[0];
    sums.stiffness_denominator = v[1];
    sums.residual_square = v[2];
    sums.reaction_square = v[3];
    c = sums.damping(dt);
    const double residual = std::sqrt(v[2]), reaction = std::sqrt(v[3]);
    if (!std::isfinite(residual))
      throw NumericalFailure("non-finite residual",
                             "dynamic relaxation at t = " + std::to_string(time) +
                                 ", pseudo-step " + std::to_string(it),
                             "check the materials and the loads of this step");
    peak_residual = std::max(peak_residual, residual);
    const double scale = std::max(reaction, peak_residual);
    relative = scale > 0 ? residual / scale : 0.0;
    // The first step's forces are those of the state before it: judge from the second on.
    if (it > 1 && relative <= tolerance) {
      commit_relaxation();
      clear_velocity();
      return it;
    }
  }
  throw NumericalFailure("dynamic relaxation did not converge in " + std::to_string(max_steps) +
                             " pseudo-steps (relative residual " + significant(relative) + ")",
                         "quasi-static equilibrium at t = " + std::to_string(time),
                         "allow more relaxation steps or take smaller load steps");
}

template <int dim>
void MechanicsSolver<dim>::central_difference(double dt, double a, double bc_time,
                                              RelaxationSums* sums) {
  loaded_ = false; // loads are evaluated at the current time only
  if (temperature_field_)
    evaluate_temperature_field(dT_target_);
  const bool linear = linear_explicit();
  if (linear) {
    // Linear elasticity without loads in the volume: f_int = K u with K assembled once per
    // set of active cells (a sparse product instead of a constitutive call per point).
    if (!explicit_matrix_ready_)
      assemble_explicit_matrix();
  } else {
    assemble(false, 1.0, hanging_);
  }
  // Net force on the DoFs: −K u on the linear path (rhs_ is not formed), f_ext − f_int else.
  if (!dirichlet_dofs_ready_)
    cache_dirichlet_dofs();
  if (!step_tables_ready_) {
    build_step_tables();
    // The linear path computes only the rows of step_rows_ below: the others stay zero. (The
    // assembly above wrote every row, and the reactions read them.)
    if (linear)
      raw_residual_ = 0;
  }
  if (linear) {
    // Only the rows the update reads: hanging and orphaned DoFs (under converted cells only)
    // are skipped, so a step costs what the FEM part still holds.
    ScopedTime timer(timings_.assembly);
    threaded_vmult(explicit_matrix_, raw_residual_, u_, &step_rows_);
    states_stale_ = true;
  }
  {
    // Local arrays in the order of owned_ (element access through Trilinos is a map lookup).
    double* u = u_.begin();
    double* v = v_.begin();
    const double* r = linear ? raw_residual_.begin() : rhs_.begin();
    const double sign = linear ? -1.0 : 1.0;
    // Relaxation steps move with the fictitious masses where they are set.
    const double* mass =
        sums && relaxation_masses_on_ ? relaxation_mass_.begin() : lumped_mass_.begin();
    const std::size_t n = owned_.n_elements();
    std::copy(u, u + n, u_previous_.begin());
    if (!sums && energy_account_on_) {
      v_previous_.resize(n);
      std::copy(v, v + n, v_previous_.begin());
    }
    if (sums && relax_acceleration_.size() != n)
      relax_acceleration_.assign(n, std::numeric_limits<double>::quiet_NaN());
    if (!sums && energy_account_on_ && linear) {
      account_stored2_ = 0;
      for (std::size_t k = 0; k < n; ++k)
        if (!step_skip_[k])
          account_stored2_ += u[k] * r[k];
    }
    if (step_force_hook_)
      step_force_hook_(StepForces(linear ? raw_residual_.begin() : rhs_.begin(), sign,
                                  step_skip_.data(), step_dirichlet_.data(), step_driven_.data()));
    // A DoF without mass ends this rank's update; every rank raises it before the compresses.
    std::optional<NumericalFailure> failure;
    const auto zero_mass = [&](std::size_t k) {
      return NumericalFailure("zero lumped mass at dof " +
                                  std::to_string(owned_.nth_index_in_set(k)),
                              "explicit step", "every material needs a positive density");
    };
    // The damped central-difference update of one DoF, in both loops below; relaxation steps
    // keep one pseudo-step.
    const double h = sums ? dt : velocity_interval(dt);
    const DampedCentralDifference step(h, dt, a);
    const auto advance_dof = [&](std::size_t k, double acc) { step.advance(v[k], u[k], acc); };
    if (!sums) {
      // Independent DoFs, split among the threads as the sparse product splits its rows (the
      // same static partition of the same local order: each thread reads what it wrote).
      const long n_rows = static_cast<long>(step_rows_.size());
      long first_bad = static_cast<long>(n); // lowest local index without mass
#pragma omp parallel for schedule(static) if (n_rows > 4000) reduction(min : first_bad)
      for (long row = 0; row < n_rows; ++row) {
        const long k = step_rows_[row];
        const double m = mass[k];
        if (!(m > 0)) {
          first_bad = std::min(first_bad, k);
          continue;
        }
        advance_dof(k, sign * r[k] / m);
      }
      if (first_bad < static_cast<long>(n))
        failure = zero_mass(static_cast<std::size_t>(first_bad));
    }
    for (std::size_t k = 0; sums && !failure && k < n; ++k) { // relaxation: a fixed order
      if (step_skip_[k])
        continue;
      const double m = mass[k];
      if (!(m > 0)) {
        failure = zero_mass(k);
        break;
      }
      const double acc = sign * r[k] / m;
      // Driven DoFs (the coupling interface; boundary values win where both apply) carry
      // internal forces of the coupled system: neither residual nor reaction.
      if (step_dirichlet_[k])
        sums->reaction_square += r[k] * r[k];
      if (step_dirichlet_[k] || step_driven_[k]) {
        relax_acceleration_[k] = acc;
      } else {
        sums->add_free(r[k], acc, relax_acceleration_[k], u[k], v[k], dt);
      }
      advance_dof(k, acc);
    }
    raise_on_every_rank(failure, comm_);
    // Later conditions overwrite earlier ones on shared DoFs (as interpolate_boundary_values);
    // boundary values take precedence over driven values.
    for (unsigned int k = 0; k < bcs_.dirichlet().size(); ++k) {
      auto& f = *bcs_.dirichlet()[k].function;
      f.set_time(bc_time);
      for (const auto& b : dirichlet_dofs_[k]) {
        const double value = f.value(b.point, b.component);
        v[b.local] = (value - u_previous_[b.local]) / dt;
        u[b.local] = value;
      }
    }
    std::size_t k = 0;
    for (const auto& entry : driven_) {
      const int slot = driven_slot_[k++];
      if (slot >= 0) {
        v[slot] = (entry.second - u_previous_[slot]) / dt;
        u[slot] = entry.second;
      }
    }
  }
  u_.compress(VectorOperation::insert);
  v_.compress(VectorOperation::insert);
  hanging_lines_.distribute(u_);
  hanging_lines_.distribute(v_);
  if (!sums && energy_account_on_)
    account_energy(dt, velocity_interval(dt), a, linear);
  // NaN must not pass silently: the first non-finite owned entry (a scan of the local array;
  // Epetra's norm is a serial, scaled BLAS call), then every rank learns of any.
  const double* uu = u_.begin();
  const long n_owned = static_cast<long>(owned_.n_elements());
  long first_bad = n_owned;
#pragma omp parallel for schedule(static) if (n_owned > 4000) reduction(min : first_bad)
  for (long k = 0; k < n_owned; ++k)
    if (!std::isfinite(uu[k]))
      first_bad = std::min(first_bad, k);
  if (Utilities::MPI::max(first_bad < n_owned ? 1 : 0, comm_) > 0) {
    NumericalFailure failure(
        "non-finite displacement",
        (sums ? "relaxation step at t = " : "explicit step at t = ") + std::to_string(time_) +
            ", dt = " + std::to_string(dt) +
            (first_bad < n_owned
                 ? ", first at DoF " + std::to_string(owned_.nth_index_in_set(first_bad))
                 : std::string(", on another rank")),
        "reduce the time step (CFL safety factor) or check the materials");
    failure.set_collective(); // every rank learnt of it above
    throw failure;
  }
}

template <int dim>
double MechanicsSolver<dim>::linear_stored_energy() {
  if (!is_setup_ || n_active_cells() == 0 || !linear_explicit())
    return n_active_cells() == 0 && is_setup_ ? 0.0 : std::numeric_limits<double>::quiet_NaN();
  if (!explicit_matrix_ready_)
    assemble_explicit_matrix();
  VectorType Ku(u_);
  explicit_matrix_.vmult(Ku, u_);
  double stored2 = 0;
  for (const auto dof : owned_)
    if (!hanging_.is_constrained(dof)) // their rows live on the masters
      stored2 += u_(dof) * Ku(dof);
  return 0.5 * Utilities::MPI::sum(stored2, comm_);
}

namespace {
// The back halves of a step's sums were formed with dt; the previous step had dt_back.
inline void scale_back(ExplicitEnergy::Step& step, double ratio) {
  step.external_back *= ratio;
  step.prescribed_back *= ratio;
  step.damping_back *= ratio;
}
} // namespace

template <int dim>
void MechanicsSolver<dim>::account_energy(double dt, double h, double a, bool linear) {
  // Per unknown (fem/explicit_energy.h): the net force F of the update (−K u on the linear
  // path, the condensed f_ext − f_int else), the raw load f_ext and f_int = raw residual +
  // f_ext on the nonlinear path. Hanging DoFs (after distribute, so their u and v are
  // current) carry raw loads only: their condensed F and their mass live on the masters.
  const std::size_t n = owned_.n_elements();
  const double* v_new = v_.begin();
  const double* mass = lumped_mass_.begin();
  const double* r = linear ? raw_residual_.begin() : rhs_.begin();
  const double* raw = raw_residual_.begin();
  const double* f_ext = linear ? nullptr : external_force_.begin();
  const double sign = linear ? -1.0 : 1.0;
  ExplicitEnergy::Step supported, driven; // Dirichlet and free DoFs; driven DoFs
  // u_n − u_{n−1} = dt_back v_{n−½}, h = ½ (dt_back + dt): steps differ where a run lands on
  // its output times (dt_back = dt at the first step).
  const double dt_back = 2 * h - dt;
  double internal_back = 0, internal_forward = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double vo = v_previous_[k], vn = v_new[k], fe = f_ext ? f_ext[k] : 0.0;
    const double back = 0.5 * dt_back * vo, forward = 0.5 * dt * vn;
    if (!linear) {
      const double f_int = raw[k] + fe;
      internal_back += f_int * back;
      internal_forward += f_int * forward;
    }
    if (step_skip_[k]) {
      supported.external_back += fe * 0.5 * dt * vo; // scaled to dt_back below, as the rest
      supported.external_forward += fe * forward;
      continue;
    }
    const bool is_driven = step_driven_[k] && !step_dirichlet_[k];
    const bool massless = is_driven && massless_driven_; // only its loads' work is booked
    (is_driven ? driven : supported)
        .add(massless ? 0.0 : mass[k], vo, vn, dt, h, sign * r[k], fe,
             step_dirichlet_[k] || (is_driven && !massless), a);
  }
  scale_back(supported, dt_back / dt);
  scale_back(driven, dt_back / dt);
  energy_.time = time_;
  energy_.external.add(supported.external_back + supported.prescribed_back + driven.external_back,
                       supported.external_forward + supported.prescribed_forward +
                           driven.external_forward);
  energy_.interface.add(driven.prescribed_back, driven.prescribed_forward);
  energy_.damping.add(supported.damping_back, supported.damping_forward);
  energy_.internal.add(internal_back, internal_forward);
  energy_.kinetic = supported.kinetic + driven.kinetic;
  energy_.kinetic_central = supported.kinetic_central + driven.kinetic_central;
  energy_.strain = linear ? 0.5 * account_stored2_ : std::numeric_limits<double>::quiet_NaN();
  energy_.valid = true;
}

template <int dim>
void MechanicsSolver<dim>::assemble_explicit_matrix() {
  DynamicSparsityPattern dsp(relevant_);
  DoFTools::make_sparsity_pattern(dof_handler_, dsp, hanging_, true);
  SparsityTools::distribute_sparsity_pattern(dsp, owned_, comm_, relevant_);
  explicit_matrix_.reinit(owned_, owned_, dsp, comm_);
  // The assembly writes the force vectors: the last step's (reactions) stay readable when the
  // matrix is built between steps (an energy account right after a conversion).
  const VectorType rhs = rhs_, raw = raw_residual_;
  assemble_into_explicit_matrix_ = true;
  assemble(true, 1.0, hanging_);
  assemble_into_explicit_matrix_ = false;
  rhs_ = rhs;
  raw_residual_ = raw;
  trial_ = committed_;
  explicit_matrix_ready_ = true;
}

template <int dim>
void MechanicsSolver<dim>::cache_dirichlet_dofs() {
  std::map<types::global_dof_index, Point<dim>> support;
  DoFTools::map_dofs_to_support_points(*mapping_, dof_handler_, support);
  dirichlet_dofs_.assign(bcs_.dirichlet().size(), {});
  for (unsigned int k = 0; k < bcs_.dirichlet().size(); ++k) {
    std::map<types::global_dof_index, double> dofs;
    BoundaryConditions<dim>::interpolate(bcs_.dirichlet()[k], *mapping_, dof_handler_,
                                         Functions::ZeroFunction<dim>(dim), dofs);
    for (const auto& [dof, zero] : dofs)
      if (owned_.is_element(dof) && !hanging_.is_constrained(dof))
        for (unsigned int c = 0; c < dim; ++c)
          if (component_dofs_[c].is_element(dof))
            dirichlet_dofs_[k].push_back(
                {dof, c, support.at(dof), static_cast<unsigned int>(owned_.index_within_set(dof))});
  }
  dirichlet_dofs_ready_ = true;
  step_tables_ready_ = false;
}

template <int dim>
bool MechanicsSolver<dim>::linear_explicit() const {
  if (prm_.kinematics != "small_strain" || body_force_ || temperature_change_ ||
      temperature_field_ || cavity_traction_ || !bcs_.traction().empty() ||
      !bcs_.pressure().empty())
    return false;
  for (const auto& [id, law] : laws_)
    if (law && law->name() != "linear_elastic")
      return false;
  for (const auto& law : cell_laws_)
    if (law && law->name() != "linear_elastic")
      return false;
  return true;
}

template <int dim>
void MechanicsSolver<dim>::build_step_tables() {
  const std::size_t n = owned_.n_elements();
  step_skip_.assign(n, 0);
  step_dirichlet_.assign(n, 0);
  step_driven_.assign(n, 0);
  std::size_t k = 0;
  for (auto it = owned_.begin(); it != owned_.end(); ++it, ++k)
    step_skip_[k] = hanging_.is_constrained(*it) || orphan_[relevant_.index_within_set(*it)];
  step_rows_.clear();
  for (std::size_t k = 0; k < n; ++k)
    if (!step_skip_[k])
      step_rows_.push_back(static_cast<int>(k));
  for (const auto& list : dirichlet_dofs_)
    for (const auto& b : list)
      step_dirichlet_[b.local] = 1;
  driven_slot_.clear();
  driven_slot_.reserve(driven_.size());
  for (const auto& [dof, value] : driven_) {
    int slot = -1;
    if (owned_.is_element(dof) && !hanging_.is_constrained(dof)) {
      const auto local = owned_.index_within_set(dof);
      if (!step_dirichlet_[local])
        slot = static_cast<int>(local);
      step_driven_[local] = 1;
    }
    driven_slot_.push_back(slot);
  }
  u_previous_.resize(n);
  hanging_lines_.build(hanging_);
  step_tables_ready_ = true;
}

template <int dim>
typename MechanicsSolver<dim>::QuasiStaticResult
MechanicsSolver<dim>::solve_quasi_static_or_relax(double time, bool relax, double tolerance,
                                                  unsigned int max_steps) {
  QuasiStaticResult result;
  try {
    result.reports = solve_quasi_static(time);
  } catch (const NumericalFailure& failure) {
    if (!relax)
      throw;
    result.newton_failure = failure.what_failed();
    result.relaxation_steps = relax_quasi_static(time, tolerance, max_steps);
  }
  return result;
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template double MechanicsSolver<dim>::stable_time_step(Point<dim>*) const;                       \
  template double MechanicsSolver<dim>::cell_step(                                                 \
      const typename DoFHandler<dim>::active_cell_iterator&, bool, std::vector<Point<dim>>&)       \
      const;                                                                                       \
  template void MechanicsSolver<dim>::explicit_step(double);                                       \
  template typename MechanicsSolver<dim>::RelaxationSums MechanicsSolver<dim>::relaxation_step(    \
      double, double, double, bool);                                                               \
  template void MechanicsSolver<dim>::clear_velocity();                                            \
  template unsigned int MechanicsSolver<dim>::relax_quasi_static(double, double, unsigned int);    \
  template typename MechanicsSolver<dim>::QuasiStaticResult                                        \
  MechanicsSolver<dim>::solve_quasi_static_or_relax(double, bool, double, unsigned int);           \
  template void MechanicsSolver<dim>::commit_relaxation();                                         \
  template void MechanicsSolver<dim>::central_difference(double, double, double, RelaxationSums*); \
  template bool MechanicsSolver<dim>::linear_explicit() const;                                     \
  template void MechanicsSolver<dim>::assemble_explicit_matrix();                                  \
  template void MechanicsSolver<dim>::cache_dirichlet_dofs();                                      \
  template void MechanicsSolver<dim>::build_step_tables();                                         \
  template void MechanicsSolver<dim>::account_energy(double, double, double, bool);                \
  template double MechanicsSolver<dim>::linear_stored_energy();
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
