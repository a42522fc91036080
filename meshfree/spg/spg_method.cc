#include "meshfree/spg/spg_method.h"

#include "base/exceptions.h"
#include "fem/materials/material_state_io.h"
#include "fem/materials/plane_strain_embedding.h"
#include "meshfree/bond_loop.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <istream>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace spinesim::meshfree {

template <int dim>
SpgMethod<dim>::SpgMethod(const Parameters& parameters, const ParticleMaterial& material)
    : prm_(parameters.solver), law_(material.law), table_(material.table),
      thickness_(parameters.thickness), reference_temperature_(material.reference_temperature) {
  if (!law_)
    throw InvalidInput("SPG", "no constitutive law", "a law from the Material section");
}

template <int dim>
typename SpgMethod<dim>::Parameters
SpgMethod<dim>::parse_parameters(const dealii::ParameterHandler& section) {
  Parameters p;
  p.solver.parse(section);
  p.thickness = section.get_double("Thickness");
  if (!(p.thickness > 0.0))
    throw InvalidInput("SPG/Thickness", "= " + std::to_string(p.thickness), "> 0 [m]");
  return p;
}

template <int dim>
void SpgMethod<dim>::declare(dealii::ParameterHandler& prm) {
  SpgParameters::declare(prm);
  prm.declare_entry("Thickness", "1", dealii::Patterns::Double(0.0),
                    "Out-of-plane thickness of a 2-D body (plane strain) [m].");
}

template <int dim>
SPGSolver<dim>& SpgMethod<dim>::solver() {
  if (!solver_)
    throw std::logic_error("SpgMethod: initialise() before use");
  return *solver_;
}

template <int dim>
double SpgMethod<dim>::search_radius(double spacing) const {
  return RKKernel<dim>::from_names(prm_.kernel, prm_.support_shape)
      .search_radius(prm_.dilation * spacing);
}

template <int dim>
typename NeighborSearch<dim>::Options SpgMethod<dim>::neighbor_options(double spacing) const {
  typename NeighborSearch<dim>::Options o;
  // The kernel's search radius (a√dim for cubic supports), so a coupled run's rows hold the
  // whole support.
  o.horizon = search_radius(spacing);
  o.partial_volume = false;
  o.surface_correction = false;
  return o;
}

template <int dim>
void SpgMethod<dim>::initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  if (dim == 2 && std::abs(particles.thickness() - thickness_) > 1e-12 * thickness_)
    throw InvalidInput("SPG/Thickness",
                       "particles were made with thickness " +
                           std::to_string(particles.thickness()) + " m, the method has " +
                           std::to_string(thickness_) + " m",
                       "the same thickness for particles and method");
  if (!(bonds.horizon > 0.0))
    throw InvalidInput("SPG", "bond list without a search radius",
                       "bonds searched with SpgMethod::neighbor_options");
  if (solver_)
    kept_ = solver_->committed_states();
  // The caller's rows carry its pre-cracks and breaks; a kernel that resets its reference
  // searches its own (SPGSolver refuses given rows for it, so a coupled run must be total
  // Lagrangian).
  const bool driven = std::find(driven_.begin(), driven_.end(), std::uint8_t(1)) != driven_.end();
  const bool use_rows = driven || prm_.kernel_update == "total_lagrangian";
  // Each particle's law: its material's from the table (reread here: it may have grown), or
  // the one law without a table.
  std::vector<const materials::ConstitutiveLaw*> law_of_particle(particles.size(), law_.get());
  std::vector<std::shared_ptr<const materials::ConstitutiveLaw>> laws{law_};
  if (table_ && !table_->empty()) {
    laws.clear();
    std::vector<std::uint8_t> used(table_->size(), 0);
    for (unsigned int i = 0; i < particles.size(); ++i) {
      const unsigned int m = particles.material_id(i);
      if (m >= table_->size())
        throw InvalidInput("SPG",
                           "particle " + std::to_string(i) + " of material " + std::to_string(m) +
                               " in a table of " + std::to_string(table_->size()) + " laws",
                           "material ids of the particles' material table");
      law_of_particle[i] = &table_->law(m);
      if (!used[m]) {
        used[m] = 1;
        laws.push_back(table_->law_pointer(m));
      }
    }
  }
  solver_ = std::make_unique<SPGSolver<dim>>(prm_, std::move(law_of_particle), particles,
                                             bonds.horizon / search_radius(1.0),
                                             use_rows ? &bonds : nullptr);
  solver_laws_ = std::move(laws); // after the old solver, which ran the old ones, is gone
  solver_->set_deferred_commit(true);
  solver_->set_breaking(breaking_);
  solver_->set_break_observer(
      [this](const std::vector<unsigned int>& rows, bool after) { observe_breaks(rows, after); });
  solver_->set_reference_temperature(reference_temperature_);
  solver_->set_break_decider(break_decider_);
  if (driven)
    solver_->set_driven(driven_);
  solver_->set_driven_gradients(driven_gradients_, takes_driven_gradient_);
  for (unsigned int i = 0; i < kept_.size() && i < particles.size(); ++i)
    solver_->set_state(i, kept_[i]);
  kept_.clear();
}

template <int dim>
std::size_t SpgMethod<dim>::compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                           bool allow_breaking) {
  // A pass that may not break (Effects/Damage = false, or the pass an energy account takes
  // before the breaks, for the forces they remove) evaluates the forces on the bonds as they are.
  const std::size_t before = solver().n_broken_bonds();
  solver_->set_breaking(breaking_ && allow_breaking);
  pass_energy_before_.assign(particles.size(), std::numeric_limits<double>::quiet_NaN());
  pass_particles_ = &particles;
  solver_->compute_forces(particles);
  pass_particles_ = nullptr;
  solver_->set_breaking(breaking_);
  const std::size_t broken = solver_->n_broken_bonds() - before;
  // The caller's rows carry the breaks too (the same rows, unless the kernel searched its own).
  if (broken > 0 && solver_->bonds().n_bonds() == bonds.n_bonds())
    bonds.broken = solver_->bonds().broken;
  return broken;
}

template <int dim>
void SpgMethod<dim>::compute_forces_before_breaks(ParticleSet<dim>& particles,
                                                  BondList<dim>& bonds) {
  solver().set_counting_step(false);
  try {
    compute_forces(particles, bonds, false);
  } catch (...) {
    solver_->set_counting_step(true);
    throw;
  }
  solver_->set_counting_step(true);
}

template <int dim>
std::string SpgMethod<dim>::user_failure_criteria() const {
  std::ostringstream out;
  if (prm_.critical_stretch > 0.0)
    out << "Critical stretch = " << prm_.critical_stretch;
  if (prm_.critical_plastic_strain > 0.0)
    out << (out.tellp() > 0 ? ", " : "")
        << "Critical plastic strain = " << prm_.critical_plastic_strain;
  return out.str();
}

template <int dim>
void SpgMethod<dim>::set_break_decider(std::function<bool(unsigned int, unsigned int)> decides) {
  break_decider_ = std::move(decides);
  if (solver_)
    solver_->set_break_decider(break_decider_);
}

template <int dim>
std::vector<std::pair<unsigned int, unsigned int>> SpgMethod<dim>::take_broken_pairs() {
  return solver().take_broken_pairs();
}

template <int dim>
void SpgMethod<dim>::break_pairs(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                 const std::vector<std::pair<unsigned int, unsigned int>>& pairs) {
  pass_energy_before_.assign(particles.size(), std::numeric_limits<double>::quiet_NaN());
  pass_particles_ = &particles;
  solver().break_pairs(particles, pairs);
  pass_particles_ = nullptr;
  if (solver_->bonds().n_bonds() == bonds.n_bonds())
    bonds.broken = solver_->bonds().broken;
}

template <int dim>
std::vector<dealii::Tensor<1, dim>>
SpgMethod<dim>::physical_displacements(const ParticleSet<dim>& particles) const {
  if (!solver_)
    return particles.displacements();
  // An updated kernel's functions belong to its last reference: u^h of the last evaluation.
  if (solver_->parameters().update_mode() != SpgKernelUpdate::total_lagrangian)
    return solver_->physical_displacements();
  return solver_->smoothed(particles.displacements());
}

template <int dim>
std::vector<double> SpgMethod<dim>::stiffness_bound(const ParticleSet<dim>& particles,
                                                    const BondList<dim>&) {
  if (!solver_) // no particles yet (a coupled run before its first conversion)
    return std::vector<double>(particles.size(), 0.0);
  return solver_->stiffness_bound(particles);
}

template <int dim>
double SpgMethod<dim>::stable_time_step(const ParticleSet<dim>&, const BondList<dim>&,
                                        double safety) {
  if (!solver_)
    return std::numeric_limits<double>::infinity();
  return safety * solver_->stable_time_step();
}

template <int dim>
dealii::Tensor<2, dim> SpgMethod<dim>::particle_gradient(unsigned int i,
                                                         const ParticleSet<dim>& particles) const {
  // From the coefficients now (a restored checkpoint has not evaluated forces yet).
  return solver_->parameters().update_mode() == SpgKernelUpdate::total_lagrangian
             ? (solver_->has_row(i) ? solver_->deformation_gradient(i, particles.displacements())
                                    : dealii::Tensor<2, dim>(dealii::unit_symmetric_tensor<dim>()))
             : solver_->deformation_gradients()[i];
}

template <int dim>
double SpgMethod<dim>::energy_density(unsigned int i, const ParticleSet<dim>& particles) const {
  if (!solver_)
    throw std::logic_error("SpgMethod: initialise() before use");
  // The share of stress kept after breaks (fracture damage D_f) scales the energy with it.
  const double kept = 1.0 - solver_->committed_states()[i].fracture_damage;
  if (!(kept > 0.0))
    return 0.0;
  // 4-point Gauss–Legendre on [0, 1].
  const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
  const double t[4] = {0.5 * (1 - b), 0.5 * (1 - a), 0.5 * (1 + a), 0.5 * (1 + b)};
  const double w[4] = {0.5 * wb, 0.5 * wa, 0.5 * wa, 0.5 * wb};
  const auto F = particle_gradient(i, particles);
  const double dT = thermal_change(particles.temperature(i));
  // A law whose stored energy is a function of its state (J2 plasticity), as in NOSB-PD: the
  // path integral below would count the plastic strain as stored, or start from a stressed
  // intermediate configuration (finite strain).
  const materials::ConstitutiveLaw& law = law_of(i);
  if (const auto W = law.stored_energy_density(materials::embed_plane_strain(F), dT,
                                               solver_->committed_states()[i]))
    return kept * *W;
  materials::Tensor2 H;
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int c = 0; c < dim; ++c)
      H[r][c] = F[r][c] - (r == c ? 1.0 : 0.0);
  double W = 0;
  for (unsigned int q = 0; q < 4; ++q) {
    const materials::Tensor2 Ft = materials::Tensor2(dealii::unit_symmetric_tensor<3>()) + t[q] * H;
    const auto r = law.finite_strain_stress(Ft, dT, solver_->committed_states()[i]);
    W += w[q] * dealii::scalar_product(r.first_piola, H);
  }
  return kept * W;
}

template <int dim>
void SpgMethod<dim>::observe_breaks(const std::vector<unsigned int>& rows, bool after) {
  if (!pass_particles_)
    return;
  const ParticleSet<dim>& p = *pass_particles_;
  // A break rebuilds the RK rows of both ends from the bonds left; at the same coefficients
  // F_i of such a row may grow (a row that lost its bonds across a crack extrapolates the
  // opening from one side), and the stored energy with it, which an explicit run turns into
  // kinetic energy (the SPG ring's fragments at 8 times the initial speed). A row whose energy
  // rose keeps the share E_before / E_after of its stress: 1 − D_f ← (1 − D_f) E_before/E_after.
  // Rises below the energy of a strain of 1e-8 over the particle's volume are round-off.
  if (!after) {
    // -1: no energy before (no row, or the law refused this F): nothing to compare after.
    energy_before_break_.assign(rows.size(), -1.0);
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (solver_->has_row(rows[k])) {
        try {
          energy_before_break_[k] = energy_density(rows[k], p) * p.volume(rows[k]);
        } catch (const NumericalFailure&) {
        }
      }
    for (std::size_t k = 0; k < rows.size(); ++k)
      if (rows[k] < pass_energy_before_.size() && std::isnan(pass_energy_before_[rows[k]]))
        pass_energy_before_[rows[k]] = std::max(energy_before_break_[k], 0.0);
    return;
  }
  for (std::size_t k = 0; k < rows.size() && k < energy_before_break_.size(); ++k) {
    const unsigned int i = rows[k];
    if (!solver_->has_row(i))
      continue;
    const double floor = 1e-16 * law_of(i).youngs_modulus(); // the row's own material
    const double before = energy_before_break_[k];
    if (before < 0.0)
      continue;
    double now = 0;
    try {
      now = energy_density(i, p) * p.volume(i);
    } catch (const NumericalFailure&) {
      // The rebuilt row inverts F (det F <= 0 at the same coefficients): it measures no
      // strain of the material left, and keeps no stress.
      solver_->scale_kept(i, 0.0);
      continue;
    }
    if (!(now > before + floor * p.volume(i)))
      continue;
    solver_->scale_kept(i, before > 0.0 ? before / now : 0.0);
  }
}

template <int dim>
double SpgMethod<dim>::row_stabilisation_energy(unsigned int i,
                                                const ParticleSet<dim>& particles) const {
  // The stabilisation energy ½ κ_i |r_i|² of row i is stored energy too (spg_solver.h): left
  // out, a ring that flows plastically (where d − ū grows) lost 0.6 % of its energy. Updated
  // kernels: the last pass's, as their F (particle_gradient).
  return solver_->parameters().update_mode() == SpgKernelUpdate::total_lagrangian
             ? solver_->stabilisation_energy(i, particles.displacements())
             : solver_->stabilisation_energy(i);
}

template <int dim>
std::vector<double> SpgMethod<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                          const BondList<dim>&) const {
  // A distributed zone's ghosts [first_ghost_, size) are counted by their owners.
  std::vector<double> W(particles.size(), 0.0);
  const unsigned int n = std::min<unsigned int>(particles.size(), first_ghost_);
  for (unsigned int i = 0; solver_ && i < n; ++i)
    W[i] =
        energy_density(i, particles) + row_stabilisation_energy(i, particles) / particles.volume(i);
  return W;
}

template <int dim>
double SpgMethod<dim>::strain_energy(const ParticleSet<dim>& particles,
                                     const BondList<dim>& bonds) const {
  const auto W = strain_energy_density(particles, bonds);
  double E = 0;
  for (unsigned int i = 0; i < particles.size(); ++i)
    E += W[i] * particles.volume(i);
  return E;
}

template <int dim>
double SpgMethod<dim>::bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                   unsigned int i, std::size_t k,
                                   const std::vector<std::uint8_t>* broken_before) const {
  const auto& before = broken_before ? *broken_before : bonds.broken;
  if (before[k])
    return 0.0;
  const auto& V = particles.volumes();
  double all = 0;
  for_each_bond_of(bonds, i, [&](std::size_t b, unsigned int j) {
    if (!before[b])
      all += bonds.volume_factor(b) * V[j];
  });
  if (!(all > 0.0))
    return 0.0;
  // The row's stored energy as the account counts it (the stabilisation energy included);
  // asked after the pass that broke k, the row's energy before that pass rebuilt it.
  const double cached = broken_before && i < pass_energy_before_.size()
                            ? pass_energy_before_[i]
                            : std::numeric_limits<double>::quiet_NaN();
  return bonds.volume_factor(k) * V[bonds.neighbor[k]] / all *
         ((std::isnan(cached) ? energy_density(i, particles) * V[i] : cached) +
          row_stabilisation_energy(i, particles));
}

template <int dim>
void SpgMethod<dim>::update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
  // The broken share of each row, as the solver sets it at a break (SPGSolver::after_breaks);
  // from the bonds alone, so a restart that restored them restores it too.
  for (unsigned int i = 0; i < particles.size() && i < bonds.n_particles(); ++i) {
    unsigned int b = 0, t = 0;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
      b += bonds.broken[k];
      ++t;
    });
    particles.damage(i) = t ? double(b) / t : 0.0;
  }
}

namespace {
// First word of an SPG material history in a particle-zone checkpoint ("SPGHIST1").
constexpr std::uint64_t spg_history_tag = 0x3154534948475053ULL;   // "SPGHIST1"
constexpr std::uint64_t spg_history_tag_2 = 0x3254534948475053ULL; // "SPGHIST2": with cadence
} // namespace

template <int dim>
void SpgMethod<dim>::save(std::ostream& out) const {
  const std::uint64_t n = solver_ ? solver_->committed_states().size() : 0;
  out.write(reinterpret_cast<const char*>(&spg_history_tag_2), sizeof(spg_history_tag_2));
  out.write(reinterpret_cast<const char*>(&n), sizeof(n));
  for (std::uint64_t i = 0; i < n; ++i) {
    const auto v = materials::pack_state(solver_->committed_states()[i]);
    out.write(reinterpret_cast<const char*>(v.data()), sizeof(double) * v.size());
  }
  // The smoothing cadence (Smoothing interval > 1 reuses the last refresh's forces).
  const std::uint64_t calls = solver_ ? solver_->step_count() : 0;
  out.write(reinterpret_cast<const char*>(&calls), sizeof(calls));
  if (n > 0)
    out.write(reinterpret_cast<const char*>(solver_->smoothing_forces().data()),
              sizeof(dealii::Tensor<1, dim>) * n);
}

template <int dim>
void SpgMethod<dim>::load(std::istream& in) {
  std::uint64_t tag = 0, n = 0;
  in.read(reinterpret_cast<char*>(&tag), sizeof(tag));
  in.read(reinterpret_cast<char*>(&n), sizeof(n));
  const std::uint64_t expected = solver_ ? solver_->committed_states().size() : 0;
  if (!in || (tag != spg_history_tag && tag != spg_history_tag_2) || n != expected)
    throw InvalidInput("SPG checkpoint", "the material history does not fit the particles",
                       "a checkpoint written by the same run");
  std::array<double, materials::material_state_doubles> v{};
  for (std::uint64_t i = 0; i < n; ++i) {
    in.read(reinterpret_cast<char*>(v.data()), sizeof(double) * v.size());
    if (!in)
      throw InvalidInput("SPG checkpoint", "truncated material history", "a complete checkpoint");
    const std::string why = materials::inadmissible_state(v);
    if (!why.empty())
      throw InvalidInput("SPG checkpoint",
                         "the material history of point " + std::to_string(i) + " holds " + why,
                         "the checkpoint as the run wrote it");
    solver_->set_state(static_cast<unsigned int>(i), materials::unpack_state(v));
  }
  if (tag != spg_history_tag_2 || n == 0)
    return; // written before the cadence was kept: the restart refreshes on its own count
  std::uint64_t calls = 0;
  std::vector<dealii::Tensor<1, dim>> smoothing(n);
  in.read(reinterpret_cast<char*>(&calls), sizeof(calls));
  in.read(reinterpret_cast<char*>(smoothing.data()), sizeof(dealii::Tensor<1, dim>) * n);
  if (!in)
    throw InvalidInput("SPG checkpoint", "truncated smoothing state", "a complete checkpoint");
  for (std::size_t i = 0; i < smoothing.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!std::isfinite(smoothing[i][d]))
        throw InvalidInput("SPG checkpoint",
                           "a non-finite smoothing force of particle " + std::to_string(i),
                           "the checkpoint as the run wrote it");
  // The restart's first force pass repeats the checkpoint's last one (same displacements):
  // it counts again, so the count resumes one lower and the cadence continues unbroken.
  solver_->set_cadence(calls > 0 ? calls - 1 : 0, std::move(smoothing));
}

template <int dim>
void SpgMethod<dim>::commit_state() {
  if (solver_)
    solver_->commit_state();
}

template <int dim>
void SpgMethod<dim>::rollback_state() {
  if (solver_)
    solver_->rollback_state();
}

template <int dim>
std::vector<HistoryRecord> SpgMethod<dim>::history(const std::vector<std::uint8_t>& which) const {
  std::vector<HistoryRecord> records;
  if (!solver_)
    return records;
  const auto& states = solver_->committed_states();
  for (unsigned int i = 0; i < states.size(); ++i)
    if ((which.empty() || (i < which.size() && which[i])) && !materials::is_virgin(states[i]))
      records.push_back({i, i, states[i]});
  return records;
}

template <int dim>
void SpgMethod<dim>::set_history(const std::vector<HistoryRecord>& records) {
  for (const auto& r : records)
    if (solver_ && r.particle == r.neighbour && r.particle < solver_->committed_states().size())
      solver_->set_state(r.particle, r.state);
}

template <int dim>
void SpgMethod<dim>::set_particle_states(const ParticleSet<dim>& particles,
                                         const std::vector<CarriedState>& states) {
  if (!solver_)
    return;
  // Each particle continues the state at its own F (total Lagrangian kernels, F from the
  // coefficients now: no force pass has run on the new rows yet); as it is elsewhere.
  const bool own_F = solver_->parameters().update_mode() == SpgKernelUpdate::total_lagrangian;
  // An inverted F keeps the state as carried: the first force pass reports it.
  for (const auto& c : states)
    if (c.particle < solver_->committed_states().size()) {
      const unsigned int i = c.particle;
      materials::MaterialState s = c.state;
      if (c.deformation && own_F && solver_->has_row(i)) {
        const materials::Tensor2 F_to = materials::embed_plane_strain(
            solver_->deformation_gradient(i, particles.displacements()));
        if (dealii::determinant(F_to) > 0.0 && dealii::determinant(*c.deformation) > 0.0)
          s = law_of(i).transferred_state(c.state, *c.deformation, F_to);
      }
      solver_->set_state(i, s);
    }
}

template <int dim>
std::vector<double> SpgMethod<dim>::plastic_work_density(const ParticleSet<dim>& particles) const {
  // Only where energy_density takes the stored energy from the state (J2 plasticity), and
  // after this update at the current F, as that W (NosbPD alike). Several materials: a particle
  // whose own law does not (elastic) holds none, as a single such law holds none.
  if (!solver_ || !has_plastic_work())
    return {};
  std::vector<double> D(particles.size(), 0.0);
  for (unsigned int i = 0; i < D.size() && i < solver_->committed_states().size(); ++i) {
    const materials::ConstitutiveLaw& law = law_of(i);
    if (!law.stored_energy_from_state())
      continue;
    const materials::MaterialState& old = solver_->committed_states()[i];
    D[i] = old.plastic_work;
    // The share kept of the update's work, as SPGSolver books it. After a pass that broke
    // bonds this reads the new share and the rebuilt row's F, while the state committed holds
    // the pass's: the difference goes to the breaks' energy release.
    if (old.fracture_damage < 1.0)
      D[i] +=
          (1.0 - old.fracture_damage) *
          (law.finite_strain_stress(materials::embed_plane_strain(particle_gradient(i, particles)),
                                    thermal_change(particles.temperature(i)), old)
               .state.plastic_work -
           old.plastic_work);
  }
  return D;
}

template <int dim>
materials::MaterialState SpgMethod<dim>::particle_state(unsigned int i) const {
  if (!solver_ || i >= solver_->committed_states().size())
    return {};
  return solver_->committed_states()[i];
}

template <int dim>
const std::vector<dealii::Tensor<1, dim>>& SpgMethod<dim>::physical_displacements() const {
  if (!solver_)
    throw std::logic_error("SpgMethod: initialise() before use");
  return solver_->physical_displacements();
}

template <int dim>
std::optional<std::vector<dealii::Tensor<1, dim>>>
SpgMethod<dim>::driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>&) const {
  if (!solver_ || driven_.size() != particles.size())
    return std::vector<dealii::Tensor<1, dim>>(particles.size());
  return solver_->driven_forces(driven_);
}

template <int dim>
std::optional<std::vector<double>>
SpgMethod<dim>::splice_energy_by_row(const ParticleSet<dim>& particles,
                                     const BondList<dim>& bonds) const {
  if (!solver_)
    return std::vector<double>(particles.size(), 0.0);
  // The smoothing force is refreshed every `Smoothing interval` steps: only with 1 is it the
  // gradient of the stabilisation energy.
  if (prm_.stabilisation > 0.0 && prm_.smoothing_interval != 1)
    return std::nullopt;
  auto E = strain_energy_density(particles, bonds); // owned rows: with their stabilisation
  for (unsigned int i = 0; i < particles.size(); ++i)
    E[i] =
        E[i] * particles.volume(i) + (i >= first_ghost_ ? solver_->stabilisation_energy(i) : 0.0);
  return E;
}

template <int dim>
std::size_t SpgMethod<dim>::memory_bytes() const {
  return (solver_ ? solver_->memory_bytes() : 0) + driven_.capacity() +
         kept_.capacity() * sizeof(materials::MaterialState) +
         solver_laws_.capacity() * sizeof(std::shared_ptr<const materials::ConstitutiveLaw>) +
         (energy_before_break_.capacity() + pass_energy_before_.capacity()) * sizeof(double);
}

template class SpgMethod<2>;
template class SpgMethod<3>;

SPINESIM_REGISTER_PARTICLE_METHOD(
    SpgMethod, "spg", "SPG",
    "smoothed particle Galerkin (Wu, Park & Chen 2015): reproducing-kernel shape functions, "
    "direct nodal integration with displacement-smoothing stabilisation, the point-wise law "
    "of the Material section, bond failure by stretch or plastic strain.")

} // namespace spinesim::meshfree
