#include "meshfree/spg/spg_solver.h"

#include "base/exceptions.h"
#include "fem/materials/plane_strain_embedding.h"
#include "fem/materials/tensor_tools.h"
#include "meshfree/bond_loop.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace spinesim::meshfree {

template <int dim>
SPGSolver<dim>::SPGSolver(const Parameters& parameters, const materials::ConstitutiveLaw& law,
                          const ParticleSet<dim>& particles, double spacing,
                          const BondList<dim>* rows)
    : SPGSolver(parameters, std::vector<const materials::ConstitutiveLaw*>(particles.size(), &law),
                particles, spacing, rows) {}

template <int dim>
SPGSolver<dim>::SPGSolver(const Parameters& parameters,
                          std::vector<const materials::ConstitutiveLaw*> law_of_particle,
                          const ParticleSet<dim>& particles, double spacing,
                          const BondList<dim>* rows)
    : prm_(parameters), mode_(parameters.update_mode()),
      kernel_(RKKernel<dim>::from_names(parameters.kernel, parameters.support_shape)) {
  prm_.validate();
  if (!(spacing > 0.0))
    throw InvalidInput("SPG spacing", "= " + spg_number(spacing), "> 0 [m]");
  if (particles.size() == 0)
    throw InvalidInput("SPG particles", "no particles", "at least one particle");
  const unsigned int n = particles.size();
  if (law_of_particle.size() != n)
    throw InvalidInput("SPG laws",
                       "laws for " + std::to_string(law_of_particle.size()) + " particles, " +
                           std::to_string(n) + " particles",
                       "one law per particle");
  h_ = spacing;
  a_ = prm_.dilation * h_;
  // The distinct laws, each with its λ + 2μ, c_p and k_c computed once (one law: exactly the
  // values a single-law solver takes, so its results do not change to the bit).
  law_index_.resize(n);
  std::unordered_map<const materials::ConstitutiveLaw*, unsigned int> index_of;
  for (unsigned int i = 0; i < n; ++i) {
    const materials::ConstitutiveLaw* law = law_of_particle[i];
    if (!law)
      throw InvalidInput("SPG laws", "no law for particle " + std::to_string(i),
                         "a law for every particle");
    const auto [it, inserted] = index_of.emplace(law, static_cast<unsigned int>(laws_.size()));
    if (inserted)
      laws_.push_back(law);
    law_index_[i] = it->second;
  }
  for (const materials::ConstitutiveLaw* law : laws_) {
    const double E = law->youngs_modulus(), nu = law->poisson_ratio();
    const double modulus = E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    modulus_.push_back(modulus);
    cp_.push_back(law->p_wave_speed());
    kc_.push_back(prm_.contact_penalty_factor * modulus * (dim == 2 ? particles.thickness() : h_));
    uniform_wave_speed_ = uniform_wave_speed_ && (cp_.size() == 1 || cp_.back() == cp_.front());
  }
  // σ = 1 before the first force pass: the step of the fastest wave.
  min_stretch_per_speed_ = 1.0 / *std::max_element(cp_.begin(), cp_.end());
  X0_ = particles.reference_positions();
  Xr_ = X0_;
  volume_ = particles.volumes();
  rk_volume_ = volume_;
  Matrix I;
  for (unsigned int d = 0; d < dim; ++d)
    I[d][d] = 1.0;
  dref_.assign(n, Vector());
  shift_.assign(n, Vector());
  uh_.assign(n, Vector());
  stab_force_.assign(n, Vector());
  residual_.assign(n, Vector());
  contact_.assign(n, Vector());
  F_.assign(n, I);
  Fr_.assign(n, I);
  P_.assign(n, Matrix());
  stress_.assign(n, Matrix());
  state_.assign(n, materials::MaterialState());
  committed_ = state_;
  kappa_.resize(n);
  for (unsigned int i = 0; i < n; ++i)
    kappa_[i] = prm_.stabilisation * modulus_[law_index_[i]] * volume_[i] / (a_ * a_);
  has_row_.assign(n, 1);
  complete_.assign(n, 1);
  if (rows) {
    if (mode_ != KernelUpdate::total_lagrangian)
      throw InvalidInput("SPG/Kernel update", "'" + prm_.kernel_update + "' with given rows",
                         "total_lagrangian (the rows of a coupled run are fixed)");
    if (rows->n_particles() != n)
      throw InvalidInput("SPG rows",
                         "rows for " + std::to_string(rows->n_particles()) + " particles, " +
                             std::to_string(n) + " particles",
                         "one (possibly empty) row per particle");
    if (rows->horizon < kernel_.search_radius(a_) * (1 - 1e-12))
      throw InvalidInput("SPG rows", "searched within " + spg_number(rows->horizon) + " m",
                         ">= the kernel's search radius " + spg_number(kernel_.search_radius(a_)) +
                             " m");
    external_rows_ = true;
    bonds_ = *rows;
    for (unsigned int i = 0; i < n; ++i)
      has_row_[i] = bonds_.end(i) > bonds_.begin(i) ? 1 : 0;
    // Complete: a row, and every partner has one.
    accumulate_over_bonds(
        bonds_, [&](unsigned int i) { return bool(has_row_[i]); },
        [&](unsigned int, std::size_t, unsigned int j, bool& complete) {
          complete = complete && has_row_[j];
        },
        [&](unsigned int i, bool complete) { complete_[i] = complete ? 1 : 0; });
    rk_ = std::make_unique<RKShapeFunctions<dim>>(kernel_, a_, prm_.max_condition_number);
    rk_->compute(Xr_, rk_volume_, bonds_, &has_row_);
    return;
  }
  rebuild_kernel(Xr_);
}

template <int dim>
void SPGSolver<dim>::rebuild_kernel(const std::vector<dealii::Point<dim>>& centres) {
  bonds_ = RKShapeFunctions<dim>::build_bonds(centres, kernel_.search_radius(a_));
  // Pairs broken before stay broken.
  if (!broken_pairs_.empty())
    for_each_bond(bonds_, [&](unsigned int i, std::size_t k, unsigned int j) {
      const unsigned long long lo = std::min(i, j), hi = std::max(i, j);
      if (std::binary_search(broken_pairs_.begin(), broken_pairs_.end(), (lo << 32) | hi))
        bonds_.broken[k] = 1;
    });
  rk_ = std::make_unique<RKShapeFunctions<dim>>(kernel_, a_, prm_.max_condition_number);
  rk_->compute(centres, rk_volume_, bonds_);
  constraints_ready_ = false;
}

template <int dim>
void SPGSolver<dim>::constrain(ParticleSet<dim>& particles, unsigned int i, unsigned int c,
                               double value) {
  if (constraints_.is_constrained(i, c))
    constraints_.set_value(i, c, value);
  else {
    constraints_.add(i, c, value);
    particles.set_fixed(i, c, true);
    constraints_ready_ = false;
  }
}

template <int dim>
void SPGSolver<dim>::reset_reference(const ParticleSet<dim>& p) {
  // uh_, F_ belong to the coefficients of the LAST evaluation (d_last_), not to p's new ones.
  const unsigned int n = p.size();
  const auto& d = d_last_;
  for (unsigned int i = 0; i < n; ++i) {
    Xr_[i] = X0_[i] + uh_[i];
    shift_[i] = uh_[i];
    dref_[i] = d[i];
    Fr_[i] = F_[i];
    rk_volume_[i] = volume_[i] * dealii::determinant(F_[i]);
  }
  rebuild_kernel(Xr_);
  ++n_resets_;
}

template <int dim>
void SPGSolver<dim>::compute_forces(ParticleSet<dim>& p) {
  const unsigned int n = p.size();
  if (n != X0_.size())
    throw InvalidInput("SPGSolver::compute_forces", "the particle count changed",
                       "the particle set the solver was built for");
  if (calls_ > 0 && counting_step_) {
    const bool reset =
        (mode_ == KernelUpdate::updated_lagrangian && calls_ % prm_.reset_interval == 0) ||
        (mode_ == KernelUpdate::adaptive_lagrangian && max_rel_ > prm_.adaptive_threshold);
    if (reset)
      reset_reference(p);
  }
  if (!constraints_ready_) {
    if (!constraints_.empty())
      constraints_.setup(n, *rk_, bonds_);
    constraints_ready_ = true;
  }
  auto& d = p.displacements();
  if (!constraints_.empty()) {
    constraints_.apply(d, dref_, shift_, false);
    constraints_.apply(p.velocities(), dref_, shift_, true);
  }

  const auto& rk = *rk_;
  const double* psi = rk.value.data();
  const Vector* grad = rk.gradient.data();
  const double* psi_t = rk.value_at_partner.data();
  const Vector* grad_t = rk.gradient_at_partner.data();
  const bool tl = mode_ == KernelUpdate::total_lagrangian;
  const bool adaptive = mode_ == KernelUpdate::adaptive_lagrangian;

  std::vector<double> work(n), sigma(n), rel(n);
  const auto& temperature = p.temperatures();
  const bool has_temperature = temperature.size() == n;
  // Pass 1, per particle N with a row: smoothed value, F, stress. A failed material update
  // names the particle of the lowest index, whatever the thread count.
  for_each_particle(bonds_, [&](unsigned int N) {
    if (!has_row_[N]) {
      sigma[N] = 1e300;
      return;
    }
    const Vector eN = d[N] - dref_[N];
    Vector ubar = rk.self_value[N] * eN;
    Matrix Frel = outer_product(eN, rk.self_gradient[N]);
    for_each_bond_of(bonds_, N, [&](std::size_t k, unsigned int j) {
      const Vector e = d[j] - dref_[j];
      ubar += psi[k] * e;
      Frel += outer_product(e, grad[k]);
    });
    for (unsigned int i = 0; i < dim; ++i)
      Frel[i][i] += 1.0;
    uh_[N] = shift_[N] + ubar;
    residual_[N] = eN - ubar;
    const bool from_driver = tl && takes_driven_gradient(N);
    const Matrix F = from_driver ? (*driven_gradients_)[N] : tl ? Frel : Frel * Fr_[N];
    const materials::Tensor2 F3 = materials::embed_plane_strain(F);
    Matrix P;
    // The share of stress kept after breaks raised the row's energy (fracture damage D_f,
    // scale_kept): a row that kept none carries no stress, whatever its F (it may have inverted).
    const double kept = 1.0 - committed_[N].fracture_damage;
    try {
      if (kept > 0.0) {
        const double dT = has_temperature && !std::isnan(reference_temperature_)
                              ? temperature[N] - reference_temperature_
                              : 0.0;
        // P_N = law_N(F_N): the particle's own law.
        const auto r = laws_[law_index_[N]]->finite_strain_stress(F3, dT, committed_[N]);
        state_[N] = r.state;
        // The row carries kept · P, so its flow dissipates kept · ΔW_p (as J2Damage books the
        // FEM's damaged points); the law's plastic strain and hardening advance as returned.
        // Booking the whole ΔW_p counted a row that kept little stress as dissipating at full
        // stress, and the energy account's plastic work outgrew all energy ever supplied.
        state_[N].plastic_work =
            committed_[N].plastic_work + kept * (r.state.plastic_work - committed_[N].plastic_work);
        for (unsigned int i = 0; i < dim; ++i)
          for (unsigned int j = 0; j < dim; ++j)
            P[i][j] = kept * r.first_piola[i][j];
      } else
        state_[N] = committed_[N];
      if (!deferred_commit_)
        committed_[N] = state_[N];
    } catch (const std::exception& e) {
      std::ostringstream where;
      where << "particle " << N << " at (" << current_position(N) << ")";
      throw NumericalFailure(std::string("material update failed: ") + e.what(), where.str(),
                             "the particle is inverted or the motion diverged: reduce the CFL "
                             "number, raise the stabilisation or refine the particles");
    }
    // Stress power V P:ΔF (trapezoidal in time).
    work[N] = 0.5 * volume_[N] * scalar_product(P + P_[N], F - F_[N]);
    F_[N] = F;
    P_[N] = P;
    if (!(kept > 0.0))
      stress_[N] = Matrix();
    else if (tl)
      stress_[N] = volume_[N] * P;
    else if (!adaptive)
      stress_[N] = volume_[N] * (P * transpose(Fr_[N]));
    else {
      // Adaptive Lagrangian chain rule (Wu, Park & Chen 2015): v σ ∇_xΨ with ∇_xΨ = F_rel⁻ᵀ
      // ∇_{X^r}Ψ.
      const double J = dealii::determinant(F);
      const Matrix cauchy = (1.0 / J) * P * transpose(F);
      stress_[N] = (J * volume_[N]) * (cauchy * transpose(invert(Frel)));
    }
    const double detF = dealii::determinant(F);
    const Matrix Finv = detF > 0 ? invert(F) : Matrix();
    // A row that keeps no stress adds no stiffness: its stretch does not limit the step.
    sigma[N] = !(kept > 0.0) ? 1e300 : detF > 0 ? 1.0 / Finv.norm() : 0.0;
    Matrix dF = Frel;
    for (unsigned int i = 0; i < dim; ++i)
      dF[i][i] -= 1.0;
    rel[N] = dF.norm();
  });
  double min_sigma = 1e300, min_per_speed = 1e300, max_rel = 0;
  for (unsigned int N = 0; N < n; ++N) {
    internal_work_ += work[N];
    min_sigma = std::min(min_sigma, sigma[N]);
    // Several wave speeds: each particle's stretch limits the step with its own c_p.
    if (!uniform_wave_speed_)
      min_per_speed = std::min(min_per_speed, sigma[N] / cp_[law_index_[N]]);
    max_rel = std::max(max_rel, rel[N]);
  }
  min_stretch_ = min_sigma;
  min_stretch_per_speed_ = uniform_wave_speed_ ? min_sigma / cp_.front() : min_per_speed;
  max_rel_ = max_rel;

  // Contact (serial over obstacles; cheap next to the law).
  std::fill(contact_.begin(), contact_.end(), Vector());
  reaction_.assign(obstacles_.size(), Vector());
  contact_energy_ = 0;
  const double offset = prm_.contact_offset * h_;
  for (unsigned int o = 0; o < obstacles_.size(); ++o)
    for (unsigned int i = 0; i < n; ++i) {
      Vector normal;
      const double g = obstacles_[o].gap(current_position(i), time_, normal) - offset;
      if (g < 0.0) {
        const double kc = kc_[law_index_[i]]; // the particle's own stiffness
        const Vector f = (-kc * g) * normal;
        contact_[i] += f;
        reaction_[o] -= f;
        contact_energy_ += 0.5 * kc * g * g;
      }
    }
  const bool has_contact = !obstacles_.empty();

  // Stabilisation energy and force.
  const bool stabilise = prm_.stabilisation > 0.0;
  const bool refresh = stabilise && (calls_ % prm_.smoothing_interval == 0);
  double es = 0, max_res = 0;
  for (unsigned int N = 0; N < n; ++N) {
    es += 0.5 * kappa_[N] * residual_[N].norm_square();
    max_res = std::max(max_res, residual_[N].norm());
  }
  stab_energy_ = stabilise ? es : 0.0;
  max_residual_ = max_res;

  // Pass 2, per particle I: gather f_I = −Σ_N S_N ∇Ψ_I(X_N) + stabilisation + contact.
  auto& force = p.forces();
  for_each_particle(bonds_, [&](unsigned int I) {
    if (!complete_[I]) { // driven from outside
      force[I] = Vector();
      return;
    }
    Vector f = -(stress_[I] * rk.self_gradient[I]);
    for_each_bond_of(bonds_, I,
                     [&](std::size_t k, unsigned int N) { f -= stress_[N] * grad_t[k]; });
    if (refresh) {
      Vector s = (rk.self_value[I] - 1.0) * kappa_[I] * residual_[I];
      for_each_bond_of(bonds_, I, [&](std::size_t k, unsigned int N) {
        s += (kappa_[N] * psi_t[k]) * residual_[N];
      });
      stab_force_[I] = s;
    }
    if (stabilise)
      f += stab_force_[I];
    if (has_contact) {
      Vector c = rk.self_value[I] * contact_[I];
      for_each_bond_of(bonds_, I,
                       [&](std::size_t k, unsigned int N) { c += psi_t[k] * contact_[N]; });
      f += c;
    }
    force[I] = f;
  });

  if (!constraints_.empty()) {
    const auto& fe = p.external_forces();
    std::vector<Vector> total(n);
    for (unsigned int i = 0; i < n; ++i)
      total[i] = force[i] + fe[i];
    constraints_.condense(total);
    for (unsigned int i = 0; i < n; ++i)
      force[i] = total[i] - fe[i];
  }
  if (breaking_ && (prm_.critical_plastic_strain > 0.0 || prm_.critical_stretch > 0.0))
    break_bonds(p);
  if (mode_ != KernelUpdate::total_lagrangian)
    d_last_ = d;
  if (counting_step_)
    ++calls_;
}

template <int dim>
void SPGSolver<dim>::set_cadence(unsigned long step_count,
                                 std::vector<dealii::Tensor<1, dim>> smoothing_forces) {
  if (smoothing_forces.size() != stab_force_.size())
    throw InvalidInput("SPG checkpoint", "smoothing forces for another particle count",
                       "a checkpoint written by the same run");
  calls_ = step_count;
  stab_force_ = std::move(smoothing_forces);
}

template <int dim>
void SPGSolver<dim>::break_bonds(ParticleSet<dim>& p) {
  const unsigned int n = p.size();
  const auto& rk = *rk_;
  std::vector<unsigned int> affected;
  const double ec = prm_.critical_plastic_strain, sc = prm_.critical_stretch;
  const bool any_driven = !driven_.empty();
  const double stretch_limit_2 = (1.0 + sc) * (1.0 + sc);
  for (unsigned int i = 0; i < n; ++i) {
    if (!has_row_[i])
      continue;
    // Serial: a break writes the reversed bond in j's row and appends to the lists in order.
    for_each_bond_of(bonds_, i, [&](std::size_t k, unsigned int j) {
      if (j < i || bonds_.broken[k] || !has_row_[j] || (any_driven && driven_[i] && driven_[j]))
        return;
      bool brk = false;
      if (ec > 0.0 &&
          0.5 * (state_[i].equivalent_plastic_strain + state_[j].equivalent_plastic_strain) > ec)
        brk = true;
      if (!brk && sc > 0.0) {
        // (L − L0) / L0 > s_c, compared as squares: no square root per bond and step.
        const double L0_2 = (X0_[j] - X0_[i]).norm_square();
        const double L_2 = (current_position(j) - current_position(i)).norm_square();
        if (L0_2 > 0.0 && L_2 > stretch_limit_2 * L0_2)
          brk = true;
      }
      if (brk && break_decider_) { // shared: decided here, broken by break_pairs()
        if (break_decider_(i, j))
          newly_broken_.emplace_back(i, j);
        return;
      }
      if (brk) {
        bonds_.broken[k] = 1;
        bonds_.broken[rk.reverse[k]] = 1;
        broken_pairs_.push_back((static_cast<unsigned long long>(i) << 32) | j);
        newly_broken_.emplace_back(i, j);
        affected.push_back(i);
        affected.push_back(j);
      }
    });
  }
  if (affected.empty())
    return;
  std::sort(broken_pairs_.begin(), broken_pairs_.end());
  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  after_breaks(p, affected);
}

template <int dim>
void SPGSolver<dim>::scale_kept(unsigned int i, double factor) {
  const double f = std::clamp(factor, 0.0, 1.0);
  committed_[i].fracture_damage = 1.0 - (1.0 - committed_[i].fracture_damage) * f;
  state_[i].fracture_damage = committed_[i].fracture_damage;
}

template <int dim>
void SPGSolver<dim>::after_breaks(ParticleSet<dim>& p, const std::vector<unsigned int>& affected) {
  if (break_observer_)
    break_observer_(affected, false);
  for (const unsigned int i : affected) {
    if (!has_row_[i])
      continue;
    rk_->recompute_row(i, Xr_, rk_volume_, bonds_);
    unsigned int b = 0, t = 0;
    for_each_bond_of(bonds_, i, [&](std::size_t k, unsigned int) {
      b += bonds_.broken[k];
      ++t;
    });
    p.damage(i) = t ? double(b) / t : 0.0;
    for (unsigned int c = 0; c < dim; ++c)
      if (constraints_.is_constrained(i, c))
        constraints_ready_ = false;
  }
  if (break_observer_)
    break_observer_(affected, true);
}

template <int dim>
std::vector<std::pair<unsigned int, unsigned int>> SPGSolver<dim>::take_broken_pairs() {
  return std::exchange(newly_broken_, {});
}

template <int dim>
void SPGSolver<dim>::break_pairs(ParticleSet<dim>& p,
                                 const std::vector<std::pair<unsigned int, unsigned int>>& pairs) {
  std::vector<unsigned int> affected;
  const auto cut = [&](unsigned int i, unsigned int j) {
    if (!has_row_[i])
      return;
    for_each_bond_of(bonds_, i, [&](std::size_t k, unsigned int partner) {
      if (partner == j && !bonds_.broken[k]) {
        bonds_.broken[k] = 1;
        affected.push_back(i);
      }
    });
  };
  for (const auto& [i, j] : pairs) {
    cut(i, j);
    cut(j, i);
    broken_pairs_.push_back((static_cast<unsigned long long>(std::min(i, j)) << 32) |
                            std::max(i, j));
  }
  std::sort(broken_pairs_.begin(), broken_pairs_.end());
  broken_pairs_.erase(std::unique(broken_pairs_.begin(), broken_pairs_.end()), broken_pairs_.end());
  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  after_breaks(p, affected);
}

template <int dim>
dealii::Tensor<2, dim>
SPGSolver<dim>::deformation_gradient(unsigned int i,
                                     const std::vector<dealii::Tensor<1, dim>>& d) const {
  if (mode_ != KernelUpdate::total_lagrangian)
    throw std::logic_error("SPGSolver::deformation_gradient: total Lagrangian kernels only");
  if (takes_driven_gradient(i))
    return (*driven_gradients_)[i];
  const auto& rk = *rk_;
  Matrix F = outer_product(d[i], rk.self_gradient[i]);
  for_each_bond_of(
      bonds_, i, [&](std::size_t k, unsigned int j) { F += outer_product(d[j], rk.gradient[k]); });
  for (unsigned int r = 0; r < dim; ++r)
    F[r][r] += 1.0;
  return F;
}

template <int dim>
double SPGSolver<dim>::stabilisation_energy(unsigned int N,
                                            const std::vector<dealii::Tensor<1, dim>>& d) const {
  if (mode_ != KernelUpdate::total_lagrangian)
    throw std::logic_error("SPGSolver::stabilisation_energy: total Lagrangian kernels only");
  if (!(prm_.stabilisation > 0.0) || N >= kappa_.size() || !has_row_[N])
    return 0.0;
  const auto& rk = *rk_;
  // r_N = e_N − ū_N with e = d − d^r, as compute_forces forms it.
  Vector r = (1.0 - rk.self_value[N]) * (d[N] - dref_[N]);
  for_each_bond_of(bonds_, N,
                   [&](std::size_t k, unsigned int j) { r -= rk.value[k] * (d[j] - dref_[j]); });
  return 0.5 * kappa_[N] * r.norm_square();
}

template <int dim>
std::vector<dealii::Tensor<1, dim>>
SPGSolver<dim>::smoothed(const std::vector<dealii::Tensor<1, dim>>& d) const {
  if (mode_ != KernelUpdate::total_lagrangian)
    throw std::logic_error("SPGSolver::smoothed: total Lagrangian kernels only");
  const auto& rk = *rk_;
  std::vector<Vector> u(d.size());
  parallel_for_rethrow(long(d.size()), parallel_particle_threshold, [&](long ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    if (!has_row_[i]) {
      u[i] = d[i];
      return;
    }
    Vector s = rk.self_value[i] * d[i];
    for_each_bond_of(bonds_, i, [&](std::size_t k, unsigned int j) { s += rk.value[k] * d[j]; });
    u[i] = s;
  });
  return u;
}

template <int dim>
double SPGSolver<dim>::stable_time_step() const {
  // One wave speed: the single-law expression, to the bit.
  return uniform_wave_speed_ ? prm_.cfl * h_ * min_stretch_ / cp_.front()
                             : prm_.cfl * h_ * min_stretch_per_speed_;
}

template <int dim>
double SPGSolver<dim>::p_wave_speed() const {
  return *std::max_element(cp_.begin(), cp_.end());
}

template <int dim>
double SPGSolver<dim>::contact_stiffness() const {
  return *std::max_element(kc_.begin(), kc_.end());
}

template <int dim>
double SPGSolver<dim>::plastic_work() const {
  double w = 0;
  for (unsigned int i = 0; i < state_.size(); ++i)
    w += volume_[i] * state_[i].plastic_work;
  return w;
}

template <int dim>
std::vector<double> SPGSolver<dim>::stiffness_bound(const ParticleSet<dim>& p) const {
  const unsigned int n = p.size();
  const auto& rk = *rk_;
  // Row sums G_N = Σ_J |∇Ψ_J(X_N)| and R_N = Σ_J |δ_NJ − Ψ_J(X_N)|.
  std::vector<double> G(n), R(n);
  parallel_for_rethrow(long(n), parallel_particle_threshold, [&](long NN) {
    const unsigned int N = static_cast<unsigned int>(NN);
    if (!has_row_[N])
      return;
    G[N] = rk.self_gradient[N].norm();
    R[N] = std::abs(1.0 - rk.self_value[N]);
    for_each_bond_of(bonds_, N, [&](std::size_t k, unsigned int) {
      G[N] += rk.gradient[k].norm();
      R[N] += std::abs(rk.value[k]);
    });
  });
  std::vector<double> S(n);
  parallel_for_rethrow(long(n), parallel_particle_threshold, [&](long II) {
    const unsigned int I = static_cast<unsigned int>(II);
    if (!complete_[I])
      return;
    // Each row N with the λ + 2μ of its own law.
    double s = volume_[I] * rk.self_gradient[I].norm() * G[I] * modulus_[law_index_[I]];
    double t = kappa_[I] * std::abs(1.0 - rk.self_value[I]) * R[I];
    for_each_bond_of(bonds_, I, [&](std::size_t k, unsigned int N) {
      s += volume_[N] * rk.gradient_at_partner[k].norm() * G[N] * modulus_[law_index_[N]];
      t += kappa_[N] * std::abs(rk.value_at_partner[k]) * R[N];
    });
    // ×2: the block rows of an isotropic C are bounded by (λ+2μ)|∇Ψ_I||∇Ψ_J| per component
    // pair only up to a factor; the bound must stay above the true row sum for stability.
    S[I] = 2.0 * (s + (prm_.stabilisation > 0 ? t : 0.0)) / volume_[I];
  });
  return S;
}

template <int dim>
std::vector<dealii::Tensor<1, dim>>
SPGSolver<dim>::driven_forces(const std::vector<std::uint8_t>& driven) const {
  // The gather of compute_forces, f_I −= S_N ∇Ψ_I(X_N) over the rows N of I's support, read
  // from each row N to the driven particles of its support (the bond k of N's row to I holds
  // ∇Ψ_I(X_N)); the stabilisation force the same way from W_stab = Σ_N ½ κ_N |r_N|².
  const unsigned int n = static_cast<unsigned int>(driven.size());
  std::vector<Vector> f(n);
  if (!rk_ || n != X0_.size())
    return f;
  const auto& rk = *rk_;
  const bool stabilise = prm_.stabilisation > 0.0;
  for (unsigned int N = 0; N < n; ++N) {
    if (!has_row_[N])
      continue;
    if (driven[N]) {
      f[N] -= stress_[N] * rk.self_gradient[N];
      if (stabilise)
        f[N] += ((rk.self_value[N] - 1.0) * kappa_[N]) * residual_[N];
    }
    for_each_bond_of(bonds_, N, [&](std::size_t k, unsigned int I) {
      if (!driven[I])
        return;
      f[I] -= stress_[N] * rk.gradient[k];
      if (stabilise)
        f[I] += (kappa_[N] * rk.value[k]) * residual_[N];
    });
  }
  return f;
}

template <int dim>
std::size_t SPGSolver<dim>::memory_bytes() const {
  std::size_t vectors = 0, matrices = 0;
  for (const auto* v :
       {&dref_, &shift_, &uh_, &stab_force_, &residual_, &contact_, &d_last_, &reaction_})
    vectors += v->capacity();
  for (const auto* m : {&F_, &P_, &Fr_, &stress_})
    matrices += m->capacity();
  return (rk_ ? rk_->memory_bytes() : 0) + bonds_.memory_bytes() +
         (X0_.capacity() + Xr_.capacity()) * sizeof(dealii::Point<dim>) +
         (volume_.capacity() + rk_volume_.capacity() + kappa_.capacity() + modulus_.capacity() +
          cp_.capacity() + kc_.capacity()) *
             sizeof(double) +
         laws_.capacity() * sizeof(const materials::ConstitutiveLaw*) +
         law_index_.capacity() * sizeof(unsigned int) + vectors * sizeof(Vector) +
         matrices * sizeof(Matrix) +
         (state_.capacity() + committed_.capacity()) * sizeof(materials::MaterialState) +
         has_row_.capacity() + complete_.capacity() + driven_.capacity() +
         newly_broken_.capacity() * sizeof(std::pair<unsigned int, unsigned int>) +
         broken_pairs_.capacity() * sizeof(unsigned long long);
}

template <int dim>
materials::SymTensor2 SPGSolver<dim>::cauchy_stress(unsigned int N,
                                                    const ParticleSet<dim>& particles) const {
  const double kept = 1.0 - committed_[N].fracture_damage;
  if (!has_row_[N] || !(kept > 0.0))
    return {};
  const auto& temperature = particles.temperatures();
  const double dT = temperature.size() == particles.size() && !std::isnan(reference_temperature_)
                        ? temperature[N] - reference_temperature_
                        : 0.0;
  const materials::ConstitutiveLaw& law = *laws_[law_index_[N]];
  const materials::Tensor2 F3 = materials::embed_plane_strain(F_[N]);
  const auto r = law.finite_strain_stress(F3, dT, committed_[N]);
  return kept * materials::cauchy_stress(law, F3, r.first_piola);
}

template class SPGSolver<2>;
template class SPGSolver<3>;

} // namespace spinesim::meshfree
