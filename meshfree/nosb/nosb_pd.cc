#include "meshfree/nosb/nosb_pd.h"

#include "base/exceptions.h"
#include "fem/materials/plane_strain_embedding.h"
#include "meshfree/bond_based_pd.h"
#include "meshfree/bond_loop.h"

#include <deal.II/lac/dynamic_sparsity_pattern.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>

namespace spinesim::meshfree {

namespace {
template <int dim>
std::string where(const ParticleSet<dim>& p, unsigned int i) {
  std::ostringstream s;
  s << "particle " << i << " at (" << p.reference_position(i) << ")";
  return s.str();
}
// The state after an update whose stress the family carries as kept · P: its flow dissipates
// kept · ΔW_p (J2Damage books the FEM's damaged points alike). With the whole ΔW_p a family that
// kept little stress went on dissipating at full stress, and the energy account's plastic work
// outgrew the energy supplied.
materials::MaterialState kept_share_of_work(materials::MaterialState updated,
                                            const materials::MaterialState& old, double kept) {
  updated.plastic_work = old.plastic_work + kept * (updated.plastic_work - old.plastic_work);
  return updated;
}
// The modulus c and s0 are matched to: bulk K (3-D), plane-strain k' (2-D) [Pa].
template <int dim>
double calibration_modulus_of(const materials::ConstitutiveLaw& law) {
  const double E = law.youngs_modulus(), nu = law.poisson_ratio();
  return dim == 3 ? E / (3.0 * (1.0 - 2.0 * nu)) : E / (2.0 * (1.0 - nu - 2.0 * nu * nu));
}
} // namespace

template <int dim>
NosbPD<dim>::NosbPD(const Parameters& parameters,
                    std::shared_ptr<const materials::ConstitutiveLaw> law)
    : prm_(parameters), law_(std::move(law)),
      influence_(
          InfluenceFunction<dim>::from_name(parameters.influence_function, parameters.alpha)) {
  if (!law_)
    throw InvalidInput("NOSB-PD", "no constitutive law", "a law from materials::create_law");
  if (!(prm_.horizon_ratio > 1.0) || !(prm_.thickness > 0.0) || !(prm_.critical_stretch >= 0.0) ||
      !(prm_.fracture_energy >= 0.0) || !(prm_.critical_plastic_strain >= 0.0) ||
      prm_.stabilization_coefficient < 0.0 || !(prm_.max_condition_number >= 1.0))
    throw InvalidInput("NOSB-PD parameters", "a value out of range",
                       "horizon ratio > 1, thickness > 0, critical stretch, Gc, critical plastic "
                       "strain, stabilization coefficient >= 0, condition number limit >= 1");
  modulus_ = calibration_modulus_of<dim>(*law_);
  short_range_ = ShortRangeForces<dim>(prm_.short_range);
}

template <int dim>
typename NeighborSearch<dim>::Options NosbPD<dim>::neighbor_options(double spacing) const {
  typename NeighborSearch<dim>::Options o;
  o.horizon = prm_.horizon_ratio * spacing;
  o.influence = influence_;
  o.partial_volume = prm_.partial_volume_correction;
  o.surface_correction = false; // K_i already accounts for truncated families
  return o;
}

template <int dim>
void NosbPD<dim>::initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  if (dim == 2 && std::abs(particles.thickness() - prm_.thickness) > 1e-12 * prm_.thickness)
    throw InvalidInput("NOSB-PD: Thickness",
                       "particles were made with thickness " +
                           std::to_string(particles.thickness()) + " m, the model has " +
                           std::to_string(prm_.thickness) + " m",
                       "the same thickness for particles and model");
  if (bonds.n_particles() != particles.size() || !(bonds.horizon > 0.0))
    throw InvalidInput("NOSB-PD", "bond list built for another particle set",
                       "bonds from NeighborSearch::build on these particles");
  auto critical_stretch_for = [&](double modulus) {
    if (prm_.critical_stretch > 0.0)
      return prm_.critical_stretch;
    if (prm_.fracture_energy > 0.0)
      return BondBasedPD<dim>::critical_stretch_from_fracture_energy(influence_, bonds.horizon,
                                                                     modulus, prm_.fracture_energy);
    return std::numeric_limits<double>::infinity();
  };
  c_ = BondBasedPD<dim>::micromodulus(influence_, bonds.horizon, modulus_, prm_.thickness);
  s0_ = critical_stretch_for(modulus_);
  // The constants of each law, reread here: the table may have grown since the last call.
  modulus_m_.clear();
  c_m_.clear();
  s0_m_.clear();
  if (uses_table()) {
    for (unsigned int i = 0; i < particles.size(); ++i)
      if (particles.material_id(i) >= table_->size())
        throw InvalidInput("NOSB-PD: material of " + where(particles, i),
                           "material " + std::to_string(particles.material_id(i)) +
                               ", the table has " + std::to_string(table_->size()),
                           "a material id of the particle method's material table");
    for (unsigned int m = 0; m < table_->size(); ++m) {
      const double K = calibration_modulus_of<dim>(table_->law(m));
      modulus_m_.push_back(K);
      c_m_.push_back(BondBasedPD<dim>::micromodulus(influence_, bonds.horizon, K, prm_.thickness));
      s0_m_.push_back(critical_stretch_for(K));
    }
  } else {
    modulus_m_.push_back(modulus_);
    c_m_.push_back(c_);
    s0_m_.push_back(s0_);
  }
  // One micromodulus for all springs unless the particles hold two materials or more.
  c_shared_ = c_;
  c_bond_.clear();
  if (uses_table() && particles.size() > 0) {
    const unsigned int m0 = particles.material_id(0);
    bool one_material = true;
    for (unsigned int i = 1; i < particles.size() && one_material; ++i)
      one_material = particles.material_id(i) == m0;
    if (one_material)
      c_shared_ = c_m_[m0];
    else {
      c_bond_.assign(bonds.n_bonds(), 0.0);
      for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
        const unsigned int mi = particles.material_id(i), mj = particles.material_id(j);
        c_bond_[k] = mi == mj ? c_m_[mi] : series_mean(c_m_[mi], c_m_[mj]);
      });
    }
  }
  const std::size_t n_history =
      prm_.stabilization == Stabilization::bond_associated ? bonds.n_bonds() : particles.size();
  committed_.assign(n_history, materials::MaterialState());
  trial_ = committed_;
  reverse_bond_.clear(); // a new bond list
  // History index -> (centre, partner); bond-associated indices are the bond indices, so the
  // indices of particle i are its bond row.
  history_keys_.resize(n_history);
  particle_history_begin_.assign(particles.size() + 1, 0);
  if (prm_.stabilization == Stabilization::bond_associated) {
    for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
      history_keys_[k] = {i, j};
    });
    std::copy_n(bonds.offsets.begin() + 1, particles.size(), particle_history_begin_.begin() + 1);
  } else {
    for (unsigned int i = 0; i < particles.size(); ++i) {
      history_keys_[i] = {i, i};
      particle_history_begin_[i + 1] = i + 1;
    }
  }
  F_particle_.assign(particles.size(), dealii::unit_symmetric_tensor<dim>());
  update_families(particles, bonds);
  // The contact springs take the bonds' micromoduli (a bond between materials their series
  // mean, as the hourglass springs).
  short_range_.initialise(
      particles, bonds, [this](std::size_t k) { return bond_micromodulus(k); }, driven_);
}

template <int dim>
void NosbPD<dim>::update_families(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  typename CorrespondenceFamilies<dim>::Options o;
  o.max_condition_number = prm_.max_condition_number;
  o.kind = CorrespondenceFamilies<dim>::Kind::particle;
  const auto newly = particle_families_.build(particles, bonds, o);
  if (prm_.stabilization == Stabilization::bond_associated) {
    o.kind = CorrespondenceFamilies<dim>::Kind::bond_associated;
    bond_families_.build(particles, bonds, o);
  }
  // Driven particles without a row (coupling ghosts beyond a horizon of the free ones) have
  // no family by design: not a failure worth a message. A distributed zone's ghosts are
  // reported by their owners.
  std::vector<unsigned int> reported;
  for (const unsigned int i : newly)
    if (i < first_ghost_ && (driven_.empty() || !driven_[i] || bonds.end(i) > bonds.begin(i)))
      reported.push_back(i);
  log_failed(particles, reported);
  one_sided_bonds_.clear();
  for (unsigned int i = 0; i < particles.size(); ++i)
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
      if (bonds.end(bonds.neighbor[k]) == bonds.begin(bonds.neighbor[k]))
        one_sided_bonds_.emplace_back(i, k);
  ++families_version_;
}

template <int dim>
void NosbPD<dim>::log_failed(const ParticleSet<dim>& particles,
                             const std::vector<unsigned int>& newly) {
  for (const unsigned int i : newly) {
    std::ostringstream s;
    s << "NOSB-PD: " << where(particles, i) << " flagged failed: shape tensor K singular or "
      << "ill-conditioned (condition number " << particle_families_.condition_numbers()[i] << " > "
      << prm_.max_condition_number << ", too few non-coplanar intact bonds); "
      << "no stress, damage 1";
    messages_.push_back(s.str());
  }
}

template <int dim>
std::vector<std::string> NosbPD<dim>::take_messages() {
  std::vector<std::string> m;
  m.swap(messages_);
  return m;
}

template <int dim>
const CorrespondenceFamilies<dim>& NosbPD<dim>::families() const {
  return prm_.stabilization == Stabilization::bond_associated ? bond_families_ : particle_families_;
}

template <int dim>
typename NosbPD<dim>::Response
NosbPD<dim>::evaluate(unsigned int e, const dealii::Tensor<2, dim>& F,
                      const ParticleSet<dim>& particles, materials::MaterialState* trial,
                      bool with_tangent) const {
  const auto& fam = families();
  const unsigned int i = fam.centre(e);
  // The family's share of stress lost at bond breaks (break_bonds): W = (1 − D_f) W_law. A
  // family that lost all of it carries nothing, whatever its F (it may have inverted).
  const materials::MaterialState& old = committed_[fam.history_index(e)];
  const double kept = 1.0 - old.fracture_damage;
  if (!(kept > 0.0)) {
    if (trial)
      *trial = old;
    return Response();
  }
  const materials::Tensor2 F3 = materials::embed_plane_strain(F);
  const double dT = thermal_change(particles.temperature(i));
  const materials::ConstitutiveLaw& law = law_of(particles, i); // the family's centre's
  Response out;
  try {
    if (with_tangent) {
      const materials::FiniteStrainResponse r = law.finite_strain(F3, dT, old);
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int J = 0; J < dim; ++J) {
          out.P[a][J] = kept * r.first_piola[a][J];
          for (unsigned int b = 0; b < dim; ++b)
            for (unsigned int L = 0; L < dim; ++L)
              out.A[a][J][b][L] = kept * r.dP_dF[a][J][b][L];
        }
      if (trial)
        *trial = kept_share_of_work(r.state, old, kept);
    } else {
      // An explicit step needs P only; the law's tangent would cost several times more.
      const materials::FiniteStrainStress r = law.finite_strain_stress(F3, dT, old);
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int J = 0; J < dim; ++J)
          out.P[a][J] = kept * r.first_piola[a][J];
      if (trial)
        *trial = kept_share_of_work(r.state, old, kept);
    }
  } catch (const NumericalFailure& f) {
    // The family's state says whether the material had failed already (damage near its
    // maximum: the crushed zone) or was still intact (a load step too large).
    std::ostringstream state;
    state << " (NOSB-PD family " << e << " of " << fam.n_families()
          << "; committed state: equivalent plastic strain " << old.equivalent_plastic_strain
          << ", stiffness damage " << law.stiffness_damage(old) << ", fracture share "
          << old.fracture_damage;
    // Within a relaxation the committed state is the last equilibrium's; the trial state
    // holds the previous evaluation of this family (the law failed before overwriting it).
    if (trial)
      state << "; at its last evaluation: equivalent plastic strain "
            << trial->equivalent_plastic_strain << ", stiffness damage "
            << law.stiffness_damage(*trial);
    if (i < F_particle_.size())
      state << "; det F of the particle's own family at the last force evaluation "
            << dealii::determinant(F_particle_[i]);
    state << ")";
    throw NumericalFailure(f.what_failed(), where(particles, i) + state.str(),
                           "det F <= 0: the load step is too large or particles interpenetrate; "
                           "use more load steps or a smaller time step");
  }
  return out;
}

template <int dim>
void NosbPD<dim>::compute_particle_gradients(const ParticleSet<dim>& particles) {
  const auto& u = particles.displacements();
  F_particle_.assign(particles.size(), dealii::unit_symmetric_tensor<dim>());
  const long n = particle_families_.n_families();
  // One family per particle: the writes never meet.
#pragma omp parallel for schedule(static) if (n > parallel_particle_threshold)
  for (long e = 0; e < n; ++e)
    F_particle_[particle_families_.centre(e)] = family_gradient(particle_families_, e, u);
}

template <int dim>
void NosbPD<dim>::compute_forces(ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  using Vec = dealii::Tensor<1, dim>;
  if (F_particle_.size() != particles.size())
    throw InvalidInput("NOSB-PD", "compute_forces before initialise",
                       "initialise(particles, bonds) first");
  const auto& u = particles.displacements();
  auto& f = particles.forces();
  for (auto& fi : f)
    fi = Vec();
  compute_particle_gradients(particles);

  const auto& fam = families();
  const long n_fam = fam.n_families();
  auto& P = family_stress_;
  P.resize(n_fam);
  const bool penalty = penalty_on(); // particle families then: centre(e) is the particle
  const auto stress = [&](unsigned int e, const dealii::Tensor<2, dim>& F) {
    P[e] = evaluate(e, F, particles, &trial_[fam.history_index(e)], false).P;
    if (penalty)
      // A family at the driving model's gradient: its F does not come from the particles'
      // displacements, so its springs' energy has no part through F on them, only the pair
      // forces below. With that part, a ghost whose springs reach across a change of material
      // pushed the free particles with a stress the FEM never had (a layered bar clear of the
      // jumps: −1.5 % at G_s = 0.1, −10.6 % at 1; exact without).
      if (!at_driven_gradient(fam.centre(e)))
        P[e] += penalty_part(fam.centre(e), F, particles, bonds).stress;
  };
  // The families' own gradients, formed per particle; then those at the driving model's.
  fam.for_each_deformation_gradient(
      u, parallel_particle_threshold, [&](unsigned int c) { return !at_driven_gradient(c); },
      stress);
  if (driven_gradients_)
    parallel_for_rethrow(n_fam, parallel_particle_threshold, [&](long e) {
      const unsigned int c = fam.centre(e);
      if (at_driven_gradient(c))
        stress(e, (*driven_gradients_)[c]);
    });
  // f_m = −Σ_e w_e P_e G_m: each family's forces sum to zero (Σ_m G_m = 0). Gathered per
  // particle in a fixed order (CorrespondenceFamilies::gather_forces): the same sums on any
  // number of threads.
  fam.gather_forces(P, f, parallel_particle_threshold);

  if (penalty) {
    // The pair part of −∂E_hg/∂u (the part through F_i is in P above).
    const auto& V = particles.volumes();
    const double Gc = penalty_coefficient();
    const long n = particles.size();
    // Each particle adds to its own force only (same order as serially).
#pragma omp parallel for schedule(static) if (n > parallel_particle_threshold)
    for (long i = 0; i < n; ++i) {
      for_each_penalty_bond(bonds, i, Gc, [&](std::size_t k, unsigned int j, double kappa) {
        const Vec& xi = bonds.xi[k];
        const Vec eta = u[j] - u[i];
        // s_i z_ij − s_j z_ji = s_i (η − (F_i − I)ξ) + s_j (η − (F_j − I)ξ): the springs of
        // i's family and of j's, each scaled like its stress by s = 1 − D_f (0 without a
        // family; a failed particle still feels its neighbours' springs)
        const double si = penalty_kept(i), sj = penalty_kept(j);
        const Vec dz =
            si * (eta - (F_particle_[i] * xi - xi)) + sj * (eta - (F_particle_[j] * xi - xi));
        f[i] += (kappa * V[i] * V[j]) * dz;
      });
    }
    // A partner without a bond row of its own (a coupled run's driven particle beyond the rows
    // kept) walks no bonds above, yet i's springs pull it too: −s_i κ V_i V_j z_ij. Serial, in
    // bond order, so the sums do not depend on the threads.
    for (const auto& [i, k] : one_sided_bonds_) {
      const double si = penalty_kept(i);
      if (bonds.broken[k] || !(si > 0.0))
        continue;
      const unsigned int j = bonds.neighbor[k];
      const double kappa = penalty_stiffness(bonds, k, bond_coefficient(k, Gc));
      const Vec z = (u[j] - u[i]) - (F_particle_[i] * bonds.xi[k] - bonds.xi[k]);
      f[j] -= (si * kappa * V[i] * V[j]) * z;
    }
  }
  short_range_.add_forces(particles, bonds, contacts_);
  for (unsigned int i = 0; i < particles.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!std::isfinite(f[i][d]))
        throw NumericalFailure("non-finite NOSB-PD force", where(particles, i),
                               "check the displacements (NaN input) and the load step");
}

template <int dim>
std::size_t NosbPD<dim>::n_contacts() const {
  std::size_t n = 0;
  for (unsigned int i = 0; i < contacts_.size() && i < first_ghost_; ++i)
    n += contacts_[i];
  return n;
}

template <int dim>
std::vector<dealii::Tensor<1, dim>>
NosbPD<dim>::joint_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                             const std::vector<std::uint8_t>& targets,
                             const std::vector<std::uint8_t>& counted) const {
  using Vec = dealii::Tensor<1, dim>;
  const unsigned int n = particles.size();
  std::vector<Vec> r(n);
  if (targets.size() != n || counted.size() != n || driven_.size() != n)
    return r;
  const auto is_free = [&](unsigned int i) { return !driven_[i]; };
  const auto& fam = families();
  const auto& P = family_stress_;
  for (unsigned int e = 0; e < fam.n_families() && e < P.size(); ++e) {
    const unsigned int c = fam.centre(e);
    const bool free_centre = is_free(c);
    if (!counted[c] || !(free_centre || targets[c]))
      continue;
    // The force on member m is −w P G_m; only the members a target meets are formed (most
    // are not: forming all of them took a fifth of a contact pull-out's run, measured).
    const auto wP = fam.weight(e) * P[e];
    const auto wanted = [&](unsigned int m) {
      return m != c && ((free_centre && targets[m]) || (targets[c] && is_free(m)));
    };
    fam.for_each_member_gradient(e, wanted, [&](unsigned int m, const Vec& g) {
      if (free_centre && targets[m])
        r[m] += -(wP * g);
      else
        r[c] -= -(wP * g);
    });
  }
  if (penalty_on()) {
    // The spring pair of a bond (free i, target j) as compute_forces adds it to f_i; the
    // target takes its opposite.
    const auto& u = particles.displacements();
    const auto& V = particles.volumes();
    const double Gc = penalty_coefficient();
    for (unsigned int i = 0; i < n; ++i) {
      if (!counted[i] || !is_free(i))
        continue;
      for_each_penalty_bond(bonds, i, Gc, [&](std::size_t k, unsigned int j, double kappa) {
        if (!targets[j])
          return;
        const Vec& xi = bonds.xi[k];
        const Vec eta = u[j] - u[i];
        const double si = penalty_kept(i), sj = penalty_kept(j);
        const Vec dz =
            si * (eta - (F_particle_[i] * xi - xi)) + sj * (eta - (F_particle_[j] * xi - xi));
        r[j] -= (kappa * V[i] * V[j]) * dz;
      });
    }
  }
  short_range_.add_reactions(particles, bonds, driven_, targets, counted, r);
  return r;
}

template <int dim>
void NosbPD<dim>::commit_state() {
  committed_ = trial_;
}

template <int dim>
std::vector<double> NosbPD<dim>::bond_plastic_strain(const BondList<dim>& bonds) {
  const std::size_t n_bonds = bonds.n_bonds();
  std::vector<double> ep(n_bonds, 0.0);
  if (prm_.stabilization != Stabilization::bond_associated) {
    for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
      if (j < committed_.size() && i < committed_.size())
        ep[k] = 0.5 *
                (committed_[i].equivalent_plastic_strain + committed_[j].equivalent_plastic_strain);
    });
    return ep;
  }
  if (reverse_bond_.size() != n_bonds) {
    // The rows do not change between rebuilds of the list (bonds only break): sorted keys
    // (i, j) -> k once, then each bond looks up (j, i).
    std::vector<std::pair<std::uint64_t, std::size_t>> keyed;
    keyed.reserve(n_bonds);
    for (unsigned int i = 0; i < bonds.n_particles(); ++i)
      for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
        keyed.emplace_back((std::uint64_t(i) << 32) | bonds.neighbor[k], k);
    std::sort(keyed.begin(), keyed.end());
    reverse_bond_.assign(n_bonds, n_bonds);
    for (unsigned int i = 0; i < bonds.n_particles(); ++i)
      for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k) {
        const std::uint64_t key = (std::uint64_t(bonds.neighbor[k]) << 32) | i;
        const auto it =
            std::lower_bound(keyed.begin(), keyed.end(), std::make_pair(key, std::size_t(0)));
        if (it != keyed.end() && it->first == key)
          reverse_bond_[k] = it->second;
      }
  }
  // A bond whose partner row is not held here (a coupled rank's one-sided bond) reads its own
  // family twice.
  for (std::size_t k = 0; k < n_bonds && k < committed_.size(); ++k) {
    const std::size_t r = reverse_bond_[k] < committed_.size() ? reverse_bond_[k] : k;
    ep[k] =
        0.5 * (committed_[k].equivalent_plastic_strain + committed_[r].equivalent_plastic_strain);
  }
  return ep;
}

template <int dim>
std::size_t NosbPD<dim>::break_bonds(ParticleSet<dim>& particles, BondList<dim>& bonds) {
  const double ec = prm_.critical_plastic_strain;
  const bool any_stretch =
      std::any_of(s0_m_.begin(), s0_m_.end(), [](double s) { return std::isfinite(s); });
  if (s0_m_.empty() || (!any_stretch && !(ec > 0.0))) // empty: before initialise
    return 0;
  // A bond between two materials breaks at the smaller critical stretch (the weaker side).
  const bool one_law = s0_m_.size() == 1;
  const std::vector<double> plastic = ec > 0.0 ? bond_plastic_strain(bonds) : std::vector<double>();
  const auto& u = particles.displacements();
  const bool any_driven = !driven_.empty();
  // Each bond decides alone (the reversed bond sees the same stretch bit for bit): a map. The
  // bonds break after the stored energy before the breaks is taken (the springs' part reads the
  // intact bonds).
  std::vector<std::uint8_t> touched(particles.size(), 0), breaking(bonds.n_bonds(), 0);
  std::atomic<std::size_t> n_broken{0};
  for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
    if (bonds.broken[k] || (any_driven && driven_[i] && driven_[j]))
      return;
    const auto y = bonds.xi[k] + (u[j] - u[i]);
    const double s0 =
        one_law ? s0_m_[0]
                : std::min(s0_m_[particles.material_id(i)], s0_m_[particles.material_id(j)]);
    const double limit = (1.0 + s0) * bonds.length[k]; // inf: no stretch criterion
    if (y.norm_square() > limit * limit ||             // |y| > (1 + s0) L, without a square root
        (ec > 0.0 && plastic[k] > ec)) {
      breaking[k] = 1;
      touched[i] = 1; // the reversed bond marks j: each thread writes its own rows only
      n_broken.fetch_add(1, std::memory_order_relaxed);
    }
  });
  if (n_broken > 0) {
    std::vector<unsigned int> changed;
    for (unsigned int i = 0; i < particles.size(); ++i)
      if (touched[i])
        changed.push_back(i);
    std::vector<double> before(changed.size());
    parallel_for_rethrow(
        static_cast<long>(changed.size()), parallel_particle_threshold,
        [&](long c) { before[c] = particle_strain_energy(changed[c], particles, bonds); });
    energy_before_breaks_.assign(particles.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t c = 0; c < changed.size(); ++c)
      energy_before_breaks_[changed[c]] = before[c];
    for (std::size_t k = 0; k < breaking.size(); ++k)
      bonds.broken[k] |= breaking[k];
    update_families(particles, bonds);
    release_energy_at_breaks(particles, bonds, changed, before);
    update_damage(particles, bonds);
  }
  return n_broken;
}

template <int dim>
void NosbPD<dim>::release_energy_at_breaks(const ParticleSet<dim>& particles,
                                           const BondList<dim>& bonds,
                                           const std::vector<unsigned int>& changed,
                                           const std::vector<double>& before) {
  // A break rebuilds the families of both ends (K and F from the bonds left). At the same
  // displacements F may then *grow*: a family that lost its hoop bonds measures the hoop
  // stretch from a few near-radial ones, and the stored energy of its centre rises, which an
  // explicit run turns into kinetic energy (fragments at 7× the initial speed on the ring).
  // A break must release energy, so a centre whose energy rose gets the fracture damage that
  // brings it back: 1 − D_f ← (1 − D_f) E_before/E_after on all its families. The energy
  // then never rises at a break, and a family that sees an opening crack in F carries
  // (almost) no stress.
  // Rises below the energy of a strain of 1e-8 over the particle's volume are round-off (a
  // fragment in rigid rotation stores ~eps^2 E): they must not damage it.
  const auto& V = particles.volumes();
  parallel_for_rethrow(static_cast<long>(changed.size()), parallel_particle_threshold, [&](long c) {
    const unsigned int i = changed[c];
    const double after = particle_strain_energy(i, particles, bonds);
    if (!(after > before[c] + 1e-16 * modulus_m_[material_index(particles, i)] * V[i]))
      return;
    const double ratio = before[c] > 0.0 ? before[c] / after : 0.0;
    for (std::size_t h = particle_history_begin_[i]; h < particle_history_begin_[i + 1]; ++h) {
      const double D = 1.0 - (1.0 - committed_[h].fracture_damage) * ratio;
      committed_[h].fracture_damage = trial_[h].fracture_damage = D;
    }
  });
}

template <int dim>
std::function<void(ParticleSet<dim>&)> NosbPD<dim>::force_function(BondList<dim>& bonds) {
  return [this, &bonds](ParticleSet<dim>& p) {
    break_bonds(p, bonds);
    compute_forces(p, bonds);
    commit_state();
  };
}

template <int dim>
void NosbPD<dim>::assemble_tangent(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                   dealii::SparsityPattern& pattern,
                                   dealii::SparseMatrix<double>& matrix) {
  using Vec = dealii::Tensor<1, dim>;
  const unsigned int n = particles.size();
  const auto& fam = families();
  // The penalty springs' Hessian couples the nodes of one particle family, as its stress does
  // (see below): the families' pattern holds it.
  const bool penalty = penalty_on();

  if (pattern.empty() || pattern_version_ != families_version_ || pattern.n_rows() != n * dim) {
    dealii::DynamicSparsityPattern nodes(n, n);
    std::vector<dealii::types::global_dof_index> list;
    std::vector<unsigned int> family_nodes;
    std::vector<Vec> family_gradients;
    auto add_family = [&](const CorrespondenceFamilies<dim>& F, unsigned int e) {
      F.expand(e, family_nodes, family_gradients);
      list.assign(family_nodes.begin(), family_nodes.end());
      std::sort(list.begin(), list.end());
      for (const auto m : list)
        nodes.add_entries(m, list.begin(), list.end(), true);
    };
    for (unsigned int e = 0; e < fam.n_families(); ++e)
      add_family(fam, e);
    for (unsigned int i = 0; i < n; ++i)
      nodes.add(i, i); // every particle keeps a diagonal (failed ones get an identity row)
    // Short-range contact couples the two ends of any bond, broken ones too.
    if (short_range_.enabled())
      for (unsigned int i = 0; i < bonds.n_particles(); ++i)
        for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
          if (short_range_.spring(k) > 0.0) {
            nodes.add(i, j);
            nodes.add(j, i);
            nodes.add(j, j);
          }
        });
    dealii::DynamicSparsityPattern dofs(n * dim, n * dim);
    for (unsigned int m = 0; m < n; ++m)
      for (auto it = nodes.begin(m); it != nodes.end(m); ++it)
        for (unsigned int a = 0; a < dim; ++a)
          for (unsigned int b = 0; b < dim; ++b)
            dofs.add(m * dim + a, it->column() * dim + b);
    matrix.clear();
    pattern.copy_from(dofs);
    matrix.reinit(pattern);
    pattern_version_ = families_version_;
  } else
    matrix = 0;

  const auto& u = particles.displacements();
  const auto& V = particles.volumes();
  const double Gc = penalty_coefficient();
  std::vector<dealii::types::global_dof_index> cols(dim);
  double vals[dim];
  // Penalty springs of a particle family i (E_hg in the header): z_ij = Σ_m c_m u_m with
  // c_m = δ_mj − δ_mi − G_m·ξ_ij over the family's nodes m, so E_hg is quadratic in u and its
  // Hessian, per component (× I), is
  //   K_mp = s_i V_i Σ_j κ_ij V_j c_m c_p = s_i V_i [E_mp − G_p·b_m − G_m·b_p + G_m·M G_p],
  // E from the δ parts alone, b_m = Σ_j κ_ij V_j (δ_mj − δ_mi) ξ_ij, M = Σ_j κ_ij V_j ξ⊗ξ:
  // O(family size²) a family, like its stress block.
  std::vector<int> local(penalty ? n : 0, -1); // node -> position in the current family
  std::vector<Vec> b_of;
  std::vector<unsigned int> node;
  std::vector<Vec> G;
  for (unsigned int e = 0; e < fam.n_families(); ++e) {
    fam.expand(e, node, G);
    const std::size_t n_nodes = node.size();
    const Response r = evaluate(e, family_gradient(fam, e, u), particles, nullptr, true);
    const double w = fam.weight(e);
    const unsigned int i = fam.centre(e);
    double sV = 0;
    dealii::Tensor<2, dim> M;
    if (penalty) {
      sV = penalty_kept(i) * V[i];
      b_of.assign(n_nodes, Vec());
      for (std::size_t q = 0; q < n_nodes; ++q)
        local[node[q]] = static_cast<int>(q);
      for_each_penalty_bond(bonds, i, Gc, [&](std::size_t k, unsigned int j, double kappa) {
        const double kv = kappa * V[j];
        const Vec& xi = bonds.xi[k];
        b_of[local[j]] += kv * xi; // j is a member: an intact bond
        b_of[0] -= kv * xi;        // the centre is the family's first node
        M += kv * dealii::outer_product(xi, xi);
        for (const auto& [row, col, sign] : {std::tuple(j, j, 1.0), std::tuple(i, i, 1.0),
                                             std::tuple(i, j, -1.0), std::tuple(j, i, -1.0)})
          for (unsigned int d = 0; d < dim; ++d)
            matrix.add(row * dim + d, col * dim + d, sign * sV * kv);
      });
    }
    for (std::size_t qm = 0; qm < n_nodes; ++qm) {
      // T[a][b][L] = w Σ_J A_aJbL G_m[J]
      dealii::Tensor<3, dim> T;
      const Vec& Gm = G[qm];
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int J = 0; J < dim; ++J)
          for (unsigned int b = 0; b < dim; ++b)
            for (unsigned int L = 0; L < dim; ++L)
              T[a][b][L] += w * r.A[a][J][b][L] * Gm[J];
      const unsigned int m = node[qm];
      const Vec bm = penalty ? b_of[qm] : Vec();
      const Vec MGm = M * Gm;
      for (std::size_t qp = 0; qp < n_nodes; ++qp) {
        const unsigned int p = node[qp];
        const Vec& Gp = G[qp];
        const double spring = penalty ? sV * (MGm * Gp - Gp * bm - Gm * b_of[qp]) : 0.0;
        for (unsigned int b = 0; b < dim; ++b)
          cols[b] = p * dim + b;
        for (unsigned int a = 0; a < dim; ++a) {
          for (unsigned int b = 0; b < dim; ++b)
            vals[b] = T[a][b] * Gp;
          vals[a] += spring;
          matrix.add(m * dim + a, dim, cols.data(), vals, false, true);
        }
      }
    }
    if (penalty)
      for (const unsigned int m : node)
        local[m] = -1;
  }
  short_range_.add_tangent(
      particles, bonds, [&](unsigned int row, unsigned int col, const dealii::Tensor<2, dim>& K) {
        for (unsigned int b = 0; b < dim; ++b)
          cols[b] = col * dim + b;
        for (unsigned int a = 0; a < dim; ++a) {
          for (unsigned int b = 0; b < dim; ++b)
            vals[b] = K[a][b];
          matrix.add(row * dim + a, dim, cols.data(), vals, false, true);
        }
      });
}

template <int dim>
std::vector<double> NosbPD<dim>::stiffness_row_sums(const ParticleSet<dim>& particles,
                                                    const BondList<dim>& bonds) {
  dealii::SparsityPattern pattern;
  dealii::SparseMatrix<double> K;
  assemble_tangent(particles, bonds, pattern, K);
  std::vector<double> R(particles.size(), 0.0);
  for (unsigned int row = 0; row < K.m(); ++row) {
    double s = 0;
    for (auto it = K.begin(row); it != K.end(row); ++it)
      s += std::abs(it->value());
    R[row / dim] = std::max(R[row / dim], s);
  }
  // The tangent holds the pairs in contact; the bound adds those about to engage (and those in
  // contact once more: conservative) and records which pairs the step or masses account for.
  short_range_.add_row_bound(particles, bonds, R);
  return R;
}

template <int dim>
std::vector<double> NosbPD<dim>::stiffness_row_bound(const ParticleSet<dim>& particles,
                                                     const BondList<dim>& bonds) {
  const auto& fam = families();
  const auto& u = particles.displacements();
  const long n_fam = fam.n_families();
  // Per family: B[a][J] = Σ_b Σ_L |A_aJbL| Σ_p |G_p,L|; rows m get w_e Σ_J |G_m,J| B[a][J].
  std::vector<dealii::Tensor<2, dim>> B(n_fam);
  parallel_for_rethrow(n_fam, parallel_particle_threshold, [&](long e) {
    const Response r = evaluate(e, family_gradient(fam, e, u), particles, nullptr, true);
    std::vector<unsigned int> node;
    std::vector<dealii::Tensor<1, dim>> G;
    fam.expand(e, node, G);
    dealii::Tensor<1, dim> g;
    for (const auto& Gq : G)
      for (unsigned int L = 0; L < dim; ++L)
        g[L] += std::abs(Gq[L]);
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int J = 0; J < dim; ++J)
        for (unsigned int b = 0; b < dim; ++b)
          for (unsigned int L = 0; L < dim; ++L)
            B[e][a][J] += std::abs(r.A[a][J][b][L]) * g[L];
  });
  std::vector<dealii::Tensor<1, dim>> rows(particles.size());
  std::vector<unsigned int> node;
  std::vector<dealii::Tensor<1, dim>> G;
  for (long e = 0; e < n_fam; ++e) {
    const double w = fam.weight(e);
    fam.expand(e, node, G);
    for (std::size_t q = 0; q < node.size(); ++q)
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int J = 0; J < dim; ++J)
          rows[node[q]][a] += w * std::abs(G[q][J]) * B[e][a][J];
  }
  std::vector<double> R(particles.size(), 0.0);
  for (unsigned int i = 0; i < R.size(); ++i)
    for (unsigned int a = 0; a < dim; ++a)
      R[i] = std::max(R[i], rows[i][a]);
  if (penalty_on()) {
    // The springs' Hessian (assemble_tangent), family i: Σ_p |K_mp| ≤ s_i V_i Σ_j κ V_j |c_m|
    // Σ_p |c_p| with Σ_p |c_p| ≤ S_j = 2 + |ξ_ij| Σ_q |G_q| and |c_m| ≤ δ_mi + δ_mj + |G_m| |ξ_ij|:
    // row m gets s_i V_i (δ_mi A_i + δ_mj κ_ij V_j S_j + |G_m| B_i), A_i = Σ_j κ V_j S_j,
    // B_i = Σ_j κ V_j |ξ_ij| S_j. O(family size) a family.
    const auto& pfam = particle_families_;
    const auto& V = particles.volumes();
    const double Gc = penalty_coefficient();
    for (unsigned int e = 0; e < pfam.n_families(); ++e) {
      const unsigned int i = pfam.centre(e);
      pfam.expand(e, node, G);
      double gsum = 0;
      for (const auto& Gq : G)
        gsum += Gq.norm();
      const double sV = penalty_kept(i) * V[i];
      double A = 0, B = 0;
      for_each_penalty_bond(bonds, i, Gc, [&](std::size_t k, unsigned int j, double kappa) {
        const double S = 2.0 + bonds.length[k] * gsum, kvs = kappa * V[j] * S;
        A += kvs;
        B += kvs * bonds.length[k];
        R[j] += sV * kvs;
      });
      R[i] += sV * A;
      for (std::size_t q = 0; q < node.size(); ++q)
        R[node[q]] += sV * G[q].norm() * B;
    }
  }
  return R;
}

template <int dim>
std::vector<double> NosbPD<dim>::relaxation_stiffness_bound(const ParticleSet<dim>& particles,
                                                            const BondList<dim>& bonds,
                                                            double safety) {
  std::vector<double> S = stiffness_row_sums(particles, bonds);
  for (unsigned int i = 0; i < S.size(); ++i)
    S[i] = safety * S[i] / (2.0 * std::sqrt(double(dim)) * particles.volume(i));
  return S;
}

template <int dim>
double NosbPD<dim>::stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                     double safety) {
  const std::vector<double> R = stiffness_row_sums(particles, bonds);
  double dt = std::numeric_limits<double>::infinity();
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (particles.mass(i) <= 0.0)
      throw NumericalFailure("non-positive particle mass", where(particles, i),
                             "set a positive density before the stable step");
    if (R[i] > 0.0)
      dt = std::min(dt, 2.0 * std::sqrt(particles.mass(i) / R[i]));
  }
  return safety * dt;
}

template <int dim>
double NosbPD<dim>::family_energy(unsigned int e, const ParticleSet<dim>& particles,
                                  const BondList<dim>& bonds) const {
  const auto& fam = families();
  const auto F = family_gradient(fam, e, particles.displacements());
  const double springs =
      penalty_on() ? penalty_part(fam.centre(e), F, particles, bonds).energy : 0.0;
  return springs + stress_energy(e, F, particles);
}

template <int dim>
typename NosbPD<dim>::PenaltyPart
NosbPD<dim>::penalty_part(unsigned int i, const dealii::Tensor<2, dim>& F_i,
                          const ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
  using Vec = dealii::Tensor<1, dim>;
  PenaltyPart out;
  const double s = penalty_kept(i);
  if (!(s > 0.0)) // failed particles included (penalty_kept)
    return out;
  const auto& u = particles.displacements();
  const auto& V = particles.volumes();
  const dealii::Tensor<2, dim> H =
      F_i - dealii::Tensor<2, dim>(dealii::unit_symmetric_tensor<dim>());
  double energy = 0;
  for_each_penalty_bond(bonds, i, penalty_coefficient(),
                        [&](std::size_t k, unsigned int j, double kappa) {
                          const Vec& xi = bonds.xi[k];
                          const Vec z = (u[j] - u[i]) - H * xi;
                          const double kv = kappa * V[j];
                          energy += kv * z.norm_square();
                          out.stress -= kv * dealii::outer_product(z, xi);
                        });
  out.energy = 0.5 * s * V[i] * energy;
  out.stress *= s;
  return out;
}

template <int dim>
double NosbPD<dim>::stress_energy(unsigned int e, const dealii::Tensor<2, dim>& F,
                                  const ParticleSet<dim>& particles) const {
  // W(F) = ∫_0^1 P(I + t(F−I)) : (F − I) dt by 4-point Gauss–Legendre on [0, 1].
  const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
  const double t[4] = {0.5 * (1 - b), 0.5 * (1 - a), 0.5 * (1 + a), 0.5 * (1 + b)};
  const double w[4] = {0.5 * wb, 0.5 * wa, 0.5 * wa, 0.5 * wb};
  const auto& fam = families();
  if (!(committed_[fam.history_index(e)].fracture_damage < 1.0))
    return 0.0; // no stress, no energy (evaluate)
  {
    // A law whose stored energy is a function of its state (J2 plasticity: W of the elastic
    // strain): the path integral below would count the plastic strain as stored, or start from
    // a stressed intermediate configuration (finite strain).
    const auto& old = committed_[fam.history_index(e)];
    const double dT = thermal_change(particles.temperature(fam.centre(e)));
    const auto& law = law_of(particles, fam.centre(e));
    if (const auto W = law.stored_energy_density(materials::embed_plane_strain(F), dT, old))
      return (1.0 - old.fracture_damage) * fam.weight(e) * *W; // W = (1 − D_f) W_law
  }
  const dealii::Tensor<2, dim> H = F - dealii::Tensor<2, dim>(dealii::unit_symmetric_tensor<dim>());
  double W = 0;
  for (unsigned int q = 0; q < 4; ++q) {
    const dealii::Tensor<2, dim> Ft =
        dealii::Tensor<2, dim>(dealii::unit_symmetric_tensor<dim>()) + t[q] * H;
    W += w[q] * dealii::scalar_product(evaluate(e, Ft, particles, nullptr, false).P, H);
  }
  return fam.weight(e) * W;
}

template <int dim>
double NosbPD<dim>::strain_energy(const ParticleSet<dim>& particles,
                                  const BondList<dim>& bonds) const {
  double E = 0;
  const auto& fam = families();
  for (unsigned int e = 0; e < fam.n_families() && fam.centre(e) < first_ghost_; ++e)
    E += family_energy(e, particles, bonds); // families come in centre order: ghosts' last
  return E + short_range_.energy(particles, bonds, first_ghost_);
}

template <int dim>
std::vector<double> NosbPD<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                       const BondList<dim>& bonds) const {
  std::vector<double> W(particles.size(), 0.0);
  const auto& fam = families();
  for (unsigned int e = 0; e < fam.n_families(); ++e)
    W[fam.centre(e)] += family_energy(e, particles, bonds);
  for (unsigned int i = 0; i < particles.size(); ++i)
    W[i] /= particles.volume(i);
  short_range_.add_energy_density(particles, bonds, W);
  return W;
}

template <int dim>
double NosbPD<dim>::particle_strain_energy(unsigned int i, const ParticleSet<dim>& particles,
                                           const BondList<dim>& bonds) const {
  const auto& fam = families();
  unsigned int lo = 0, hi = fam.n_families(); // first family with centre >= i
  while (lo < hi) {
    const unsigned int mid = lo + (hi - lo) / 2;
    if (fam.centre(mid) < i)
      lo = mid + 1;
    else
      hi = mid;
  }
  double E = 0;
  for (unsigned int e = lo; e < fam.n_families() && fam.centre(e) == i; ++e)
    E += family_energy(e, particles, bonds);
  return E;
}

template <int dim>
void NosbPD<dim>::set_committed_states(const std::vector<materials::MaterialState>& states) {
  if (states.size() != committed_.size())
    throw InvalidInput("NOSB-PD material history",
                       "has " + std::to_string(states.size()) + " states, the model " +
                           std::to_string(committed_.size()),
                       "one state per family history index of the same particles and bonds");
  committed_ = states;
  trial_ = states;
}

template <int dim>
bool NosbPD<dim>::set_committed_state(std::pair<unsigned int, unsigned int> key,
                                      const materials::MaterialState& state) {
  const unsigned int i = key.first;
  if (i + 1 >= particle_history_begin_.size())
    return false;
  for (std::size_t h = particle_history_begin_[i]; h < particle_history_begin_[i + 1]; ++h)
    if (history_keys_[h] == key) {
      committed_[h] = trial_[h] = state;
      return true;
    }
  return false;
}

template <int dim>
void NosbPD<dim>::set_particle_state(unsigned int i, const materials::MaterialState& state) {
  if (i + 1 >= particle_history_begin_.size())
    return;
  // The fracture damage belongs to the particle's families, not to the state brought in (an
  // FEM point's, when a converted cell takes over a ghost particle): it is kept.
  for (std::size_t h = particle_history_begin_[i]; h < particle_history_begin_[i + 1]; ++h) {
    const double D = std::max(committed_[h].fracture_damage, state.fracture_damage);
    committed_[h] = trial_[h] = state;
    committed_[h].fracture_damage = trial_[h].fracture_damage = D;
  }
}

template <int dim>
void NosbPD<dim>::set_particle_state(unsigned int i, const materials::MaterialState& state,
                                     const materials::Tensor2& F_from,
                                     const std::vector<int>& family,
                                     const ParticleSet<dim>& particles) {
  if (i + 1 >= particle_history_begin_.size())
    return;
  const auto& fam = families();
  for (std::size_t h = particle_history_begin_[i]; h < particle_history_begin_[i + 1]; ++h) {
    materials::MaterialState s = state;
    // An inverted family keeps the state as carried: its first force pass reports it.
    if (h < family.size() && family[h] >= 0) {
      const materials::Tensor2 F_to =
          materials::embed_plane_strain(family_gradient(fam, family[h], particles.displacements()));
      if (dealii::determinant(F_to) > 0.0 && dealii::determinant(F_from) > 0.0)
        s = law_of(particles, i).transferred_state(state, F_from, F_to);
    }
    const double D = std::max(committed_[h].fracture_damage, s.fracture_damage);
    committed_[h] = trial_[h] = s;
    committed_[h].fracture_damage = trial_[h].fracture_damage = D;
  }
}

template <int dim>
std::vector<double> NosbPD<dim>::plastic_work_density(const ParticleSet<dim>& particles) const {
  // Only where stress_energy takes the stored energy from the state: a path integral of a
  // plastic law is not split into stored and dissipated work.
  // With several laws, only the families whose centre runs such a law.
  const bool mixed = uses_table();
  if (!(mixed ? table_->any_stored_energy_from_state() : law_->stored_energy_from_state()))
    return {};
  std::vector<double> D(particles.size(), 0.0);
  const auto& fam = families();
  for (unsigned int e = 0; e < fam.n_families(); ++e) {
    const unsigned int i = fam.centre(e);
    if (mixed && i < D.size() && !law_of(particles, i).stored_energy_from_state())
      continue;
    if (i < D.size() && fam.history_index(e) < committed_.size())
      D[i] += fam.weight(e) * committed_[fam.history_index(e)].plastic_work / particles.volume(i);
  }
  return D;
}

template <int dim>
std::vector<int> NosbPD<dim>::family_of_history() const {
  std::vector<int> family(committed_.size(), -1);
  const auto& fam = families();
  for (unsigned int e = 0; e < fam.n_families(); ++e)
    if (fam.history_index(e) < family.size())
      family[fam.history_index(e)] = static_cast<int>(e);
  return family;
}

template <int dim>
materials::MaterialState NosbPD<dim>::particle_state(unsigned int i) const {
  if (i + 1 >= particle_history_begin_.size())
    return {};
  const std::size_t b = particle_history_begin_[i], e = particle_history_begin_[i + 1];
  if (e == b)
    return {};
  if (prm_.stabilization != Stabilization::bond_associated)
    return committed_[b];
  // The arithmetic mean over the particle's bond families (their weights differ only by the
  // partial volumes on a lattice), broken bonds included: their history is the particle's too.
  materials::MaterialState mean;
  mean.elastic_left_cauchy_green = materials::SymTensor2();
  for (std::size_t h = b; h < e; ++h) {
    const auto& s = committed_[h];
    mean.plastic_strain += s.plastic_strain;
    mean.elastic_left_cauchy_green += s.elastic_left_cauchy_green;
    mean.equivalent_plastic_strain += s.equivalent_plastic_strain;
    mean.plastic_work += s.plastic_work;
    mean.fracture_damage += s.fracture_damage;
  }
  const double total = static_cast<double>(e - b);
  mean.plastic_strain /= total;
  mean.elastic_left_cauchy_green /= total;
  mean.equivalent_plastic_strain /= total;
  mean.plastic_work /= total;
  mean.fracture_damage /= total;
  return mean;
}

template <int dim>
typename NosbPD<dim>::HourglassMeasure NosbPD<dim>::hourglass(const ParticleSet<dim>& particles,
                                                              const BondList<dim>& bonds) const {
  using Vec = dealii::Tensor<1, dim>;
  const auto& u = particles.displacements();
  const auto& V = particles.volumes();
  const auto& pfam = particle_families_;
  std::vector<dealii::Tensor<2, dim>> F(particles.size(), dealii::unit_symmetric_tensor<dim>());
  for (unsigned int e = 0; e < pfam.n_families(); ++e)
    F[pfam.centre(e)] = family_gradient(pfam, e, u);
  HourglassMeasure h;
  double z2 = 0, eta2 = 0;
  // Sums over all bonds in one fixed order (serial): the order fixes the result.
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (failed(i))
      continue;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (bonds.broken[k])
        return;
      const Vec& xi = bonds.xi[k];
      const Vec eta = u[j] - u[i];
      const Vec z = eta - (F[i] * xi - xi);
      const double wb = bonds.influence[k] * bonds.volume_factor(k) * V[i] * V[j];
      const double L = bonds.length[k];
      h.energy += 0.25 * bond_micromodulus(k) * wb * z.norm_square() / L;
      z2 += wb * z.norm_square() / (L * L);
      eta2 += wb * eta.norm_square() / (L * L);
      h.max_nonuniform = std::max(h.max_nonuniform, z.norm());
    });
  }
  h.relative_norm = eta2 > 0 ? std::sqrt(z2 / eta2) : 0.0;
  return h;
}

template <int dim>
void NosbPD<dim>::update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
  const auto& V = particles.volumes();
  struct Weights {
    double intact = 0, all = 0;
  };
  accumulate_over_bonds(
      bonds, [](unsigned int) { return Weights(); },
      [&](unsigned int, std::size_t k, unsigned int j, Weights& w) {
        const double wk = bonds.influence[k] * bonds.volume_factor(k) * V[j];
        w.all += wk;
        if (!bonds.broken[k])
          w.intact += wk;
      },
      [&](unsigned int i, const Weights& w) {
        particles.damage(i) = failed(i) ? 1.0 : (w.all > 0.0 ? 1.0 - w.intact / w.all : 0.0);
      });
}

template class NosbPD<2>;
template class NosbPD<3>;

} // namespace spinesim::meshfree
