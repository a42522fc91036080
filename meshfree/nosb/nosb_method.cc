#include "meshfree/nosb/nosb_method.h"

#include "base/exceptions.h"
#include "fem/materials/material_state_io.h"
#include "meshfree/bond_loop.h"

#include <array>
#include <cmath>
#include <istream>
#include <limits>
#include <ostream>

namespace spinesim::meshfree {

namespace {
// First word of the material history in a checkpoint written with the fracture damage
// ("NOSBHIS2"); earlier files start with the state count and hold one number fewer a state.
constexpr std::uint64_t history_tag_with_fracture_damage = 0x3253494842534f4eULL;
// Marks the short-range pairs born closer that follow the history ("NOSBSRB1").
constexpr std::uint64_t short_range_births_tag = 0x3142525342534f4eULL;

void write_state(std::ostream& out, const materials::MaterialState& s) {
  const auto v = materials::pack_state(s);
  out.write(reinterpret_cast<const char*>(v.data()), sizeof(double) * v.size());
}

// A family's state from a checkpoint; bad input naming the family when no law could have
// written it.
materials::MaterialState read_state(std::istream& in, bool with_fracture_damage,
                                    std::uint64_t family) {
  std::array<double, materials::material_state_doubles> v{};
  const std::size_t n = with_fracture_damage ? v.size() : v.size() - 1;
  in.read(reinterpret_cast<char*>(v.data()), sizeof(double) * n);
  if (in) {
    const std::string why = materials::inadmissible_state(v);
    if (!why.empty())
      throw InvalidInput("NOSB-PD checkpoint",
                         "the material history of family " + std::to_string(family) + " holds " +
                             why,
                         "the checkpoint as the run wrote it");
  }
  return materials::unpack_state(v);
}

// The model's default law: the material's, else the first of its table (null: none, which
// NosbPD reports).
std::shared_ptr<const materials::ConstitutiveLaw> default_law(const ParticleMaterial& material) {
  if (material.law || !material.table || material.table->empty())
    return material.law;
  return material.table->law_pointer(0);
}
} // namespace

template <int dim>
NosbMethod<dim>::NosbMethod(const Parameters& parameters, const ParticleMaterial& material)
    : pd_(parameters, default_law(material)), table_(material.table) {
  pd_.set_reference_temperature(material.reference_temperature);
  pd_.set_material_table(table_);
}

template <int dim>
typename NosbMethod<dim>::Parameters
NosbMethod<dim>::parse_parameters(const dealii::ParameterHandler& section) {
  Parameters p;
  p.parse(section);
  return p;
}

template <int dim>
void NosbMethod<dim>::declare(dealii::ParameterHandler& prm) {
  NosbParameters::declare(prm);
}

template <int dim>
typename NeighborSearch<dim>::Options NosbMethod<dim>::neighbor_options(double spacing) const {
  return pd_.neighbor_options(spacing);
}

template <int dim>
void NosbMethod<dim>::initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  const auto kept = history({});
  pd_.initialise(particles, bonds);
  set_history(kept);
}

template <int dim>
std::vector<HistoryRecord> NosbMethod<dim>::history(const std::vector<std::uint8_t>& which) const {
  const auto& keys = pd_.history_keys();
  const auto& states = pd_.committed_states();
  std::vector<HistoryRecord> records;
  for (std::size_t h = 0; h < keys.size() && h < states.size(); ++h) {
    const auto [i, j] = keys[h];
    if (!which.empty() && (i >= which.size() || !which[i]))
      continue;
    if (!materials::is_virgin(states[h]))
      records.push_back({i, j, states[h]});
  }
  return records;
}

template <int dim>
void NosbMethod<dim>::set_history(const std::vector<HistoryRecord>& records) {
  for (const auto& r : records)
    pd_.set_committed_state({r.particle, r.neighbour}, r.state);
}

template <int dim>
void NosbMethod<dim>::set_particle_states(const ParticleSet<dim>& particles,
                                          const std::vector<CarriedState>& states) {
  const std::vector<int> family = pd_.family_of_history();
  for (const auto& c : states)
    if (c.deformation)
      pd_.set_particle_state(c.particle, c.state, *c.deformation, family, particles);
    else
      pd_.set_particle_state(c.particle, c.state);
}

template <int dim>
std::size_t NosbMethod<dim>::compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                            bool allow_breaking) {
  const std::size_t broken = allow_breaking ? pd_.break_bonds(particles, bonds) : 0;
  pd_.compute_forces(particles, bonds);
  return broken;
}

template <int dim>
std::vector<double> NosbMethod<dim>::stiffness_bound(const ParticleSet<dim>& particles,
                                                     const BondList<dim>& bonds) {
  // The family bound (NosbPD::stiffness_row_bound): assembling the tangent for its exact row
  // sums costs a family's size squared, minutes for bond-associated families in 3-D. S_i as
  // NosbPD::relaxation_stiffness_bound forms it from R_i.
  std::vector<double> S = pd_.stiffness_row_bound(particles, bonds);
  for (unsigned int i = 0; i < S.size(); ++i)
    S[i] /= 2.0 * std::sqrt(double(dim)) * particles.volume(i);
  return S;
}

template <int dim>
void NosbMethod<dim>::add_contact_bound(const ParticleSet<dim>& particles,
                                        const BondList<dim>& bonds, std::vector<double>& S) const {
  if (!pd_.short_range().enabled())
    return;
  std::vector<double> R(particles.size(), 0.0);
  pd_.short_range().add_row_bound(particles, bonds, R);
  for (unsigned int i = 0; i < R.size() && i < S.size(); ++i)
    S[i] += R[i] / (2.0 * std::sqrt(double(dim)) * particles.volume(i)); // as stiffness_bound
}

template <int dim>
double NosbMethod<dim>::stable_time_step(const ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds, double safety) {
  // Central differences: Δt ≤ 2/ω_max, Gershgorin on M⁻¹K with the family bound of R_i and
  // the short-range pairs' rows.
  std::vector<double> R = pd_.stiffness_row_bound(particles, bonds);
  pd_.short_range().add_row_bound(particles, bonds, R);
  double dt = std::numeric_limits<double>::infinity();
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (!(particles.mass(i) > 0.0))
      throw NumericalFailure("non-positive particle mass",
                             "particle " + std::to_string(i) + " (NOSB-PD stable step)",
                             "set a positive density before the stable step");
    if (R[i] > 0.0)
      dt = std::min(dt, 2.0 * std::sqrt(particles.mass(i) / R[i]));
  }
  return safety * dt;
}

template <int dim>
std::vector<double> NosbMethod<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                           const BondList<dim>& bonds) const {
  return pd_.strain_energy_density(particles, bonds);
}

template <int dim>
double NosbMethod<dim>::strain_energy(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) const {
  return pd_.strain_energy(particles, bonds);
}

template <int dim>
double NosbMethod<dim>::bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                    unsigned int i, std::size_t k,
                                    const std::vector<std::uint8_t>* broken_before) const {
  const auto& before = broken_before ? *broken_before : bonds.broken;
  // Asked after the pass that broke k: the particle's energy from before that pass's breaks
  // rebuilt its family (which may have failed it), as the account releases it.
  const double cached =
      broken_before ? pd_.energy_before_last_breaks(i) : std::numeric_limits<double>::quiet_NaN();
  if (before[k] || (std::isnan(cached) && pd_.failed(i)))
    return 0.0;
  const auto& V = particles.volumes();
  double all = 0;
  for_each_bond_of(bonds, i, [&](std::size_t b, unsigned int j) {
    if (!before[b])
      all += bonds.influence[b] * bonds.volume_factor(b) * V[j];
  });
  if (!(all > 0.0))
    return 0.0;
  const double share = bonds.influence[k] * bonds.volume_factor(k) * V[bonds.neighbor[k]] / all;
  return share * (std::isnan(cached) ? pd_.particle_strain_energy(i, particles, bonds) : cached);
}

template <int dim>
void NosbMethod<dim>::update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
  pd_.update_damage(particles, bonds);
}

template <int dim>
void NosbMethod<dim>::save(std::ostream& out) const {
  const auto& states = pd_.committed_states();
  const std::uint64_t n = states.size();
  out.write(reinterpret_cast<const char*>(&history_tag_with_fracture_damage),
            sizeof(history_tag_with_fracture_damage));
  out.write(reinterpret_cast<const char*>(&n), sizeof(n));
  for (const auto& s : states)
    write_state(out, s);
  // The short-range pairs born closer than their reference distance, when the forces are on.
  if (pd_.short_range().enabled()) {
    const auto births = pd_.short_range().births();
    const std::uint64_t nb = births.size();
    out.write(reinterpret_cast<const char*>(&short_range_births_tag),
              sizeof(short_range_births_tag));
    out.write(reinterpret_cast<const char*>(&nb), sizeof(nb));
    for (const auto& b : births) {
      const std::uint32_t ij[2] = {b.i, b.j};
      out.write(reinterpret_cast<const char*>(ij), sizeof(ij));
      out.write(reinterpret_cast<const char*>(&b.reach), sizeof(b.reach));
    }
  }
}

template <int dim>
void NosbMethod<dim>::load(std::istream& in) {
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof(n));
  const bool with_fracture_damage = n == history_tag_with_fracture_damage;
  if (with_fracture_damage)
    in.read(reinterpret_cast<char*>(&n), sizeof(n));
  if (!in || n != pd_.committed_states().size())
    throw InvalidInput("NOSB-PD checkpoint", "the material history does not fit the particles",
                       "a checkpoint written by the same run");
  std::vector<materials::MaterialState> states;
  states.reserve(n);
  for (std::uint64_t k = 0; k < n; ++k)
    states.push_back(read_state(in, with_fracture_damage, k));
  if (!in)
    throw InvalidInput("NOSB-PD checkpoint", "truncated material history", "a complete checkpoint");
  pd_.set_committed_states(states);
  if (pd_.short_range().enabled()) {
    std::uint64_t tag = 0, nb = 0;
    in.read(reinterpret_cast<char*>(&tag), sizeof(tag));
    in.read(reinterpret_cast<char*>(&nb), sizeof(nb));
    if (!in || tag != short_range_births_tag || nb > pd_.short_range().n_bonds())
      throw InvalidInput("NOSB-PD checkpoint", "no short-range pairs after the material history",
                         "a checkpoint written with the same Short-range forces setting");
    std::vector<ShortRangeBirth> births(nb);
    for (auto& b : births) {
      std::uint32_t ij[2] = {0, 0};
      in.read(reinterpret_cast<char*>(ij), sizeof(ij));
      in.read(reinterpret_cast<char*>(&b.reach), sizeof(b.reach));
      b.i = ij[0];
      b.j = ij[1];
      if (!in || !(b.reach > 0.0) || !std::isfinite(b.reach))
        throw InvalidInput("NOSB-PD checkpoint", "truncated or damaged short-range pairs",
                           "a complete checkpoint");
    }
    pd_.restore_short_range_births(births);
  }
}

template <int dim>
std::optional<std::vector<dealii::Tensor<1, dim>>>
NosbMethod<dim>::driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>&) const {
  // compute_forces() gathers f_m = −Σ_e w_e P_e G_m over every family with a row, on every
  // member m, and adds the penalty springs' pair forces of every row to both ends (to a
  // partner without a row too): on a driven particle that is the gradient of the counted
  // energy already.
  std::vector<dealii::Tensor<1, dim>> r(particles.size());
  for (unsigned int i = 0; i < particles.size() && driven_.size() == particles.size(); ++i)
    if (driven_[i])
      r[i] = particles.force(i);
  return r;
}

template <int dim>
std::optional<std::vector<double>>
NosbMethod<dim>::splice_energy_by_row(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) const {
  // By family centre, per volume; the penalty springs of a family go with it.
  auto E = pd_.strain_energy_density(particles, bonds);
  for (unsigned int i = 0; i < particles.size(); ++i)
    E[i] *= particles.volume(i);
  return E;
}

template class NosbMethod<2>;
template class NosbMethod<3>;

SPINESIM_REGISTER_PARTICLE_METHOD(
    NosbMethod, "nosb", "NOSB",
    "non-ordinary state-based peridynamics (correspondence model, Silling et al. 2007) with "
    "the point-wise law of the Material section: any Poisson ratio, plasticity, bond-associated "
    "or penalty zero-energy-mode control, critical-stretch fracture.")

} // namespace spinesim::meshfree
