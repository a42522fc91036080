#ifndef SPINESIM_MESHFREE_BOND_BASED_PD_H
#define SPINESIM_MESHFREE_BOND_BASED_PD_H

// Bond-based peridynamics (prototype microelastic brittle, PMB): the force model only; the
// neighbour loop is meshfree/bond_loop.h, time stepping meshfree/velocity_verlet.h and
// meshfree/adaptive_dynamic_relaxation.h.
//
// Bond force density (stretch form, see influence_function.h):
//     f_ij = c ω(ξ) β G s μ n,   s = e/ξ,  e = |ξ + η| − |ξ|,  n = (ξ + η)/|ξ + η|,
// β partial volume, G surface correction, μ ∈ {0,1} the (irreversible) bond state. With the
// fractional kernel ω = ξ·ω_α this is Jo & Ha's (2021) f = c_α ω_α e μ n (their eq. 7).
// Force on particle i: F_i = V_i Σ_j k_ij e n with the precomputed bond stiffness
// k_ij = c ω β G V_j / ξ [N/m^4]. Bond energy (the force is its gradient):
//     w_ij = ½ c ω β G e²/ξ  per unit volume², W_i = ½ Σ_j w_ij V_j = ¼ Σ_j k_ij e².
//
// Bond-based PD has a fixed Poisson ratio (1/4 in 3-D and plane strain, 1/3 in plane stress);
// the micromodulus is calibrated to the bulk modulus (isotropic extension), as in Jo & Ha (2021).

#include "meshfree/bond_based_parameters.h"
#include "meshfree/bond_list.h"
#include "meshfree/influence_function.h"
#include "meshfree/material_table.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_set.h"

#include <string>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class BondBasedPD {
 public:
  using PlaneModel = meshfree::PlaneModel;
  using Parameters = BondBasedParameters;

  // E [Pa], ν [-] from the material; InvalidInput if out of range.
  BondBasedPD(const Parameters& parameters, double youngs_modulus, double poisson_ratio);

  const Parameters& parameters() const { return prm_; }
  const InfluenceFunction<dim>& influence() const { return influence_; }

  // Search options for a particle spacing h: δ = (horizon ratio)·h and the corrections.
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const;

  // The modulus the micromodulus is matched to: bulk K = E/(3(1−2ν)) in 3-D; in 2-D the
  // in-plane bulk modulus k' = E/(2(1−ν)) (plane stress) or E/(2(1−ν−2ν²)) (plane strain).
  double calibration_modulus() const { return modulus_; }

  // Micromodulus c for horizon δ, matched to the modulus above [N/m^6 for the constant kernel].
  static double micromodulus(const InfluenceFunction<dim>& omega, double delta, double modulus,
                             double thickness);
  // Critical stretch from G_c [J/m^2] (energy to break every bond across a unit crack area).
  static double critical_stretch_from_fracture_energy(const InfluenceFunction<dim>& omega,
                                                      double delta, double modulus,
                                                      double fracture_energy);
  double micromodulus(double delta) const;
  // s_0 [-]: the parameter if > 0, else from G_c, else +infinity (no damage).
  double critical_stretch(double delta) const;

  // Particles of several materials: particle i is calibrated to (*table)[material_id(i)]'s
  // E and ν, a bond between two materials takes the series mean of their micromoduli
  // (meshfree/material_table.h). Null: every particle has the constructor's E and ν.
  void set_material_table(std::shared_ptr<const MaterialTable> table) { table_ = std::move(table); }
  // The calibration modulus above for E [Pa] and ν [-].
  double calibration_modulus(double youngs_modulus, double poisson_ratio) const;

  // Precomputes k_ij for these particles and bonds. Call again when volumes or bonds change.
  // InvalidInput if the particle thickness differs from the parameter (2-D).
  void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds);
  const std::vector<double>& bond_stiffness() const { return k_; }

  // Internal forces into particles.force() [N]; breaks bonds whose stretch exceeds s_0 (if
  // allowed). Returns the number of bond ends broken in this call (each pair counts twice).
  // NumericalFailure naming the particle on a non-finite force.
  std::size_t compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                             bool allow_breaking = true) const;
  // The same on particles [begin, end) only, with no parallel region of its own: for callers
  // that split the particles among their own threads (VelocityVerlet's range form), which
  // saves a fork/join per step. Safe to call concurrently on disjoint ranges. A non-finite
  // force is not checked here (it shows in the acceleration check of the caller).
  std::size_t compute_forces_range(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                   std::size_t begin, std::size_t end,
                                   bool allow_breaking = true) const;
  // Particles per work unit of the force loops: large enough to amortise the scheduling, small
  // enough (≈ 100 units at 27 000 particles) that a descheduled thread's share is picked up.
  static constexpr std::size_t force_chunk = 256;

  // Damage φ_i = 1 − Σ_intact ω β V_j / Σ_all ω β V_j into particles.damage().
  void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const;

  std::vector<double> strain_energy_density(const ParticleSet<dim>& particles,
                                            const BondList<dim>& bonds) const; // W_i [J/m^3]
  double strain_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const; // [J]
  // Energy bond k of particle i holds at the current displacements, its share of W_i V_i
  // (¼ k_ij e² V_i, the reverse bond holds the other half): what breaking it dissipates [J].
  double bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k) const;

  // S_i = Σ_j k_ij = Σ_j V_j C_ij, C_ij = c ω β G/ξ the linearised bond stiffness [N/m^4].
  std::vector<double> stiffness_bound(const BondList<dim>& bonds) const;
  // Silling & Askari (2005): Δt = safety · min_i sqrt(2 ρ_i / S_i) [s].
  double stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                          double safety) const;

 private:
  Parameters prm_;
  InfluenceFunction<dim> influence_;
  double E_, nu_, modulus_;
  double c_ = 0, s0_ = 0;
  std::vector<double> k_;
  std::shared_ptr<const MaterialTable> table_;
};

} // namespace spinesim::meshfree

#endif
