#include "meshfree/bond_based_pd.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"
#include "meshfree/pmb_force_rows.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
BondBasedPD<dim>::BondBasedPD(const Parameters& parameters, double youngs_modulus,
                              double poisson_ratio)
    : prm_(parameters), influence_(InfluenceFunction<dim>::from_name(parameters.influence_function,
                                                                     parameters.alpha)),
      E_(youngs_modulus), nu_(poisson_ratio) {
  if (!(E_ > 0.0) || !std::isfinite(E_))
    throw InvalidInput("bond-based PD: Young's modulus", "E = " + std::to_string(E_), "E > 0 [Pa]");
  if (!(nu_ > -1.0 && nu_ < 0.5))
    throw InvalidInput("bond-based PD: Poisson ratio", "nu = " + std::to_string(nu_),
                       "-1 < nu < 0.5");
  if (!(prm_.horizon_ratio > 1.0) || !(prm_.thickness > 0.0) || prm_.critical_stretch < 0.0 ||
      prm_.fracture_energy < 0.0)
    throw InvalidInput("bond-based PD parameters",
                       "horizon ratio, thickness, critical stretch or "
                       "fracture energy out of range",
                       "horizon ratio > 1, thickness > 0, critical stretch >= 0, Gc >= 0");
  modulus_ = calibration_modulus(E_, nu_);
}

template <int dim>
double BondBasedPD<dim>::calibration_modulus(double E, double nu) const {
  if (dim == 3)
    return E / (3.0 * (1.0 - 2.0 * nu));
  if (prm_.plane_model == PlaneModel::plane_stress)
    return E / (2.0 * (1.0 - nu));
  return E / (2.0 * (1.0 - nu - 2.0 * nu * nu));
}

template <int dim>
typename NeighborSearch<dim>::Options BondBasedPD<dim>::neighbor_options(double spacing) const {
  typename NeighborSearch<dim>::Options o;
  o.horizon = prm_.horizon_ratio * spacing;
  o.influence = influence_;
  o.partial_volume = prm_.partial_volume_correction;
  o.surface_correction = prm_.surface_correction;
  return o;
}

// Micromodulus from isotropic extension (s the same in every bond), m_n = ∫_0^δ ω ξ^n dξ.
// PD energy density W = ½ ∫_H ½ c ω s² ξ dV (bond energy ½ c ω e²/ξ with e = s ξ).
//
// 2-D (dV = T ξ dξ dθ): W = ½ · ½ c s² · 2π T m_2 = (π T c m_2 / 2) s². Classical, ε = s I₂:
//   W = ½ σ:ε = 2 k' s² (σ = 2k' s I₂, k' = E/(2(1−ν)) plane stress, E/(2(1−ν−2ν²)) plane
//   strain). Hence c = 4 k' / (π T m_2). Fractional ω = ξ^(−1−α): m_2 = δ^(2−α)/(2−α) gives
//   c = 4 k' (2−α)/(π T δ^(2−α)), Jo & Ha (2021), eq. (13); constant ω: c = 12 k'/(π T δ³) =
//   9E/(π T δ³) at ν = 1/3 plane stress.
// 3-D (dV = 4π ξ² dξ averaged over directions): W = ½ · ½ c s² · 4π m_3 = π c m_3 s².
//   Classical, ε = s I: W = ½ · 3K s · 3s = (9/2) K s². Hence c = 9K/(2π m_3). Fractional
//   ω = ξ·ξ^(−3−α) = ξ^(−2−α): m_3 = ∫ ξ^(1−α) dξ = δ^(2−α)/(2−α), so
//   c_α = 9 K (2−α) / (2π δ^(2−α))   (3-D analogue of eq. 13; units N·m^(α−4), consistent
//   with f = c_α ω_α e in N/m^6 — a δ^(3−α) scaling would not be). Constant ω (α = −2):
//   c = 18K/(π δ⁴), Silling & Askari (2005).
template <int dim>
double BondBasedPD<dim>::micromodulus(const InfluenceFunction<dim>& omega, double delta,
                                      double modulus, double thickness) {
  if (dim == 2)
    return 4.0 * modulus / (M_PI * thickness * omega.moment(2, delta));
  return 9.0 * modulus / (2.0 * M_PI * omega.moment(3, delta));
}

// Critical stretch: G_c is the energy of all bonds crossing a unit crack area, each holding
// ½ c ω s0² ξ per unit volume² at breaking (Silling & Askari 2005).
// 3-D: G_c = ∫_0^δ dz ∫_z^δ dξ ∫_0^acos(z/ξ) 2π ξ² sinφ dφ · ½ c ω s0² ξ; the φ integral is
//   1 − z/ξ, and ∫_0^ξ (1 − z/ξ) dz = ξ/2, so G_c = (π c s0²/2) m_4. With c = 9K/(2π m_3):
//   s0 = sqrt(4 G_c m_3 / (9 K m_4));  constant ω: sqrt(5 G_c/(9 K δ)).
// 2-D (per unit length and thickness): the angular range is 2 acos(z/ξ) and
//   ∫_0^ξ 2 acos(z/ξ) dz = 2ξ, so G_c = T c s0² m_3. With c = 4k'/(π T m_2):
//   s0 = sqrt(π G_c m_2 / (4 k' m_3));  constant ω, ν = 1/3 plane stress: sqrt(4π G_c/(9Eδ)).
template <int dim>
double BondBasedPD<dim>::critical_stretch_from_fracture_energy(const InfluenceFunction<dim>& omega,
                                                               double delta, double modulus,
                                                               double fracture_energy) {
  if (dim == 2)
    return std::sqrt(M_PI * fracture_energy * omega.moment(2, delta) /
                     (4.0 * modulus * omega.moment(3, delta)));
  return std::sqrt(4.0 * fracture_energy * omega.moment(3, delta) /
                   (9.0 * modulus * omega.moment(4, delta)));
}

template <int dim>
double BondBasedPD<dim>::micromodulus(double delta) const {
  return micromodulus(influence_, delta, modulus_, prm_.thickness);
}

template <int dim>
double BondBasedPD<dim>::critical_stretch(double delta) const {
  if (prm_.critical_stretch > 0.0)
    return prm_.critical_stretch;
  if (prm_.fracture_energy > 0.0)
    return critical_stretch_from_fracture_energy(influence_, delta, modulus_, prm_.fracture_energy);
  return std::numeric_limits<double>::infinity();
}

template <int dim>
void BondBasedPD<dim>::initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) {
  if (dim == 2 && std::abs(particles.thickness() - prm_.thickness) > 1e-12 * prm_.thickness)
    throw InvalidInput("bond-based PD: Thickness",
                       "particles were made with thickness " +
                           std::to_string(particles.thickness()) + " m, the model has " +
                           std::to_string(prm_.thickness) + " m",
                       "the same thickness for particles and model");
  if (bonds.n_particles() != particles.size())
    throw InvalidInput("bond-based PD", "bond list built for another particle set",
                       "bonds from NeighborSearch::build on these particles");
  c_ = micromodulus(bonds.horizon);
  s0_ = critical_stretch(bonds.horizon);
  k_.resize(bonds.n_bonds());
  const auto& V = particles.volumes();
  if (!table_ || table_->empty()) {
    for_each_bond(bonds, [&](unsigned int, std::size_t k, unsigned int j) {
      k_[k] = c_ * bonds.influence[k] * bonds.volume_factor(k) * bonds.surface(k) * V[j] /
              bonds.length[k];
    });
    return;
  }
  // Several materials: c per law; a bond within one material keeps that law's c exactly.
  std::vector<double> c(table_->size()), s0(table_->size());
  for (unsigned int m = 0; m < table_->size(); ++m) {
    const double modulus =
        calibration_modulus((*table_)[m].youngs_modulus, (*table_)[m].poisson_ratio);
    c[m] = micromodulus(influence_, bonds.horizon, modulus, prm_.thickness);
    s0[m] = prm_.critical_stretch > 0.0 ? prm_.critical_stretch
            : prm_.fracture_energy > 0.0
                ? critical_stretch_from_fracture_energy(influence_, bonds.horizon, modulus,
                                                        prm_.fracture_energy)
                : std::numeric_limits<double>::infinity();
  }
  const auto& id = particles.material_ids();
  // One G_c gives each material its own s0 ∝ sqrt(G_c/K); the force kernel takes one s0.
  // Only the laws the particles run count.
  double s0_min = std::numeric_limits<double>::infinity(), s0_max = 0;
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (id[i] >= table_->size())
      throw InvalidInput("bond-based PD: material of particle " + std::to_string(i),
                         "material " + std::to_string(id[i]) + ", the table has " +
                             std::to_string(table_->size()),
                         "a material id of the particle method's material table");
    s0_min = std::min(s0_min, s0[id[i]]);
    s0_max = std::max(s0_max, s0[id[i]]);
  }
  if (particles.size() > 0 && s0_min != s0_max)
    throw InvalidInput("Bond based/Fracture energy",
                       "particles of several materials get critical stretches from " +
                           std::to_string(s0_min) + " to " + std::to_string(s0_max) +
                           " from one fracture energy, but bond-based PD takes one",
                       "Bond based/Critical stretch > 0 (one critical stretch for all bonds), "
                       "or Effects/Particles method = nosb or spg");
  s0_ = particles.size() > 0 ? s0[id[0]] : s0_;
  for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
    const double cij = id[i] == id[j] ? c[id[i]] : series_mean(c[id[i]], c[id[j]]);
    k_[k] = cij * bonds.influence[k] * bonds.volume_factor(k) * bonds.surface(k) * V[j] /
            bonds.length[k];
  });
}

namespace {
// The force loop's view of the particles and bonds (meshfree/pmb_force_rows.h).
template <int dim>
PmbForceRows<dim> make_kernel(ParticleSet<dim>& particles, BondList<dim>& bonds,
                              const std::vector<double>& k, double s0) {
  static_assert(sizeof(dealii::Point<dim>) == dim * sizeof(double) &&
                    sizeof(dealii::Tensor<1, dim>) == dim * sizeof(double),
                "points and vectors are read as packed doubles");
  return {&particles.reference_positions()[0][0],
          &particles.displacements()[0][0],
          &particles.forces()[0][0],
          particles.volumes().data(),
          bonds.offsets.data(),
          bonds.neighbor.data(),
          bonds.length.data(),
          k.data(),
          bonds.broken.data(),
          s0};
}

template <int dim>
[[noreturn]] void throw_non_finite_force(const ParticleSet<dim>& particles) {
  for (unsigned int i = 0; i < particles.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!std::isfinite(particles.force(i)[d])) {
        std::ostringstream where;
        where << "particle " << i << " at (" << particles.reference_position(i) << ")";
        throw NumericalFailure("non-finite peridynamic force", where.str(),
                               "two particles may coincide (zero bond length) or the time "
                               "step is too large; check the stable time step");
      }
  throw NumericalFailure("non-finite peridynamic force", "unknown particle",
                         "the force changed while it was being checked");
}
} // namespace

template <int dim>
std::size_t BondBasedPD<dim>::compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                             bool allow_breaking) const {
  if (k_.size() != bonds.n_bonds())
    throw InvalidInput("bond-based PD", "compute_forces before initialise",
                       "initialise(particles, bonds) first");
  const std::size_t n = particles.size();
  if (n == 0)
    return 0;
  // s0 = +inf never breaks: e > inf is false (and false for NaN, which then shows in f).
  const double s0 =
      allow_breaking && std::isfinite(s0_) ? s0_ : std::numeric_limits<double>::infinity();
  const PmbForceRows<dim> kernel = make_kernel(particles, bonds, k_, s0);

  std::size_t total = 0;
  int bad = 0;
  // Dynamic chunks of force_chunk particles: on a shared machine a descheduled thread does
  // not hold the others at the barrier; each row is still summed by one thread in order.
  const long n_chunks = static_cast<long>((n + force_chunk - 1) / force_chunk);
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : total) reduction(| : bad)             \
    if (bonds.n_bonds() > parallel_bond_threshold)
  for (long c = 0; c < n_chunks; ++c) {
    const std::size_t begin = static_cast<std::size_t>(c) * force_chunk;
    total += pmb_force_rows(kernel, begin, std::min(n, begin + force_chunk), bad);
  }
  if (bad) // located outside the parallel region: exceptions must not cross it
    throw_non_finite_force(particles);
  return total;
}

template <int dim>
std::size_t BondBasedPD<dim>::compute_forces_range(ParticleSet<dim>& particles,
                                                   BondList<dim>& bonds, std::size_t begin,
                                                   std::size_t end, bool allow_breaking) const {
  if (k_.size() != bonds.n_bonds())
    throw InvalidInput("bond-based PD", "compute_forces before initialise",
                       "initialise(particles, bonds) first");
  const double s0 =
      allow_breaking && std::isfinite(s0_) ? s0_ : std::numeric_limits<double>::infinity();
  int bad = 0; // a non-finite force reaches the acceleration, where the caller checks it
  return pmb_force_rows(make_kernel(particles, bonds, k_, s0), begin,
                        std::min<std::size_t>(end, particles.size()), bad);
}

template <int dim>
void BondBasedPD<dim>::update_damage(ParticleSet<dim>& particles,
                                     const BondList<dim>& bonds) const {
  const double* V = particles.volumes().data();
  double* phi = particles.damages().data();
  struct Acc {
    double intact, all;
  };
  accumulate_over_bonds(
      bonds,
      [](unsigned int) {
        return Acc{0.0, 0.0};
      },
      [&](unsigned int, std::size_t k, unsigned int j, Acc& acc) {
        const double w = bonds.influence[k] * bonds.volume_factor(k) * V[j];
        acc.all += w;
        if (!bonds.broken[k])
          acc.intact += w;
      },
      [&](unsigned int i, const Acc& acc) {
        phi[i] = acc.all > 0.0 ? 1.0 - acc.intact / acc.all : 0.0;
      });
}

template <int dim>
std::vector<double> BondBasedPD<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                            const BondList<dim>& bonds) const {
  using Vec = dealii::Tensor<1, dim>;
  std::vector<double> W(particles.size());
  const Vec* u = particles.displacements().data();
  accumulate_over_bonds(
      bonds, [](unsigned int) { return 0.0; },
      [&](unsigned int i, std::size_t k, unsigned int j, double& acc) {
        if (bonds.broken[k])
          return;
        const double e = (bonds.xi[k] + (u[j] - u[i])).norm() - bonds.length[k];
        acc += 0.25 * k_[k] * e * e;
      },
      [&](unsigned int i, double acc) { W[i] = acc; });
  return W;
}

template <int dim>
double BondBasedPD<dim>::bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                     unsigned int i, std::size_t k) const {
  const unsigned int j = bonds.neighbor[k];
  const double e = (bonds.xi[k] + (particles.displacement(j) - particles.displacement(i))).norm() -
                   bonds.length[k];
  return 0.25 * k_[k] * e * e * particles.volume(i);
}

template <int dim>
double BondBasedPD<dim>::strain_energy(const ParticleSet<dim>& particles,
                                       const BondList<dim>& bonds) const {
  const std::vector<double> W = strain_energy_density(particles, bonds);
  double total = 0; // serial sum: bitwise repeatable
  for (unsigned int i = 0; i < particles.size(); ++i)
    total += W[i] * particles.volume(i);
  return total;
}

template <int dim>
std::vector<double> BondBasedPD<dim>::stiffness_bound(const BondList<dim>& bonds) const {
  std::vector<double> S(bonds.n_particles());
  accumulate_over_bonds(
      bonds, [](unsigned int) { return 0.0; },
      [&](unsigned int, std::size_t k, unsigned int, double& acc) { acc += k_[k]; },
      [&](unsigned int i, double acc) { S[i] = acc; });
  return S;
}

template <int dim>
double BondBasedPD<dim>::stable_time_step(const ParticleSet<dim>& particles,
                                          const BondList<dim>& bonds, double safety) const {
  const std::vector<double> S = stiffness_bound(bonds);
  double dt = std::numeric_limits<double>::infinity();
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (S[i] > 0.0)
      dt = std::min(dt, std::sqrt(2.0 * particles.density(i) / S[i]));
  return safety * dt;
}

template class BondBasedPD<2>;
template class BondBasedPD<3>;

} // namespace spinesim::meshfree
