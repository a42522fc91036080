#ifndef SPINESIM_FEM_MATERIALS_CONSTITUTIVE_LAW_H
#define SPINESIM_FEM_MATERIALS_CONSTITUTIVE_LAW_H

// Point-wise constitutive laws shared by FEM quadrature points and particles.
// Everything is 3-D: a 2-D plane-strain caller embeds its strain/F with zero out-of-plane
// components; plane stress is handled by the law's plane_stress_* helpers (see each law).

#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <memory>
#include <optional>
#include <string>

namespace spinesim::materials {

using SymTensor2 = dealii::SymmetricTensor<2, 3>;
using SymTensor4 = dealii::SymmetricTensor<4, 3>;
using Tensor2 = dealii::Tensor<2, 3>;
using Tensor4 = dealii::Tensor<4, 3>;

// History of one material point. One plain struct for every law keeps particles'
// structure-of-arrays and FEM quadrature storage simple; each law uses what it needs.
struct MaterialState {
  SymTensor2 plastic_strain; // small-strain J2: plastic strain ε_p [-]
  SymTensor2 elastic_left_cauchy_green =
      dealii::unit_symmetric_tensor<3>(); // finite-strain J2: b^e [-]
  double equivalent_plastic_strain = 0;   // accumulated ε̄_p [-]
  double plastic_work = 0;                // dissipated plastic work per unit volume [J/m^3]
  // Share D_f of the stress the point has lost to fracture of its neighbourhood [-], imposed
  // from outside the law: a NOSB-PD family scales its stress by 1 − D_f after bond breaks so
  // that a break never raises the stored energy. Every law passes it through unchanged.
  double fracture_damage = 0;
};

// What a law returns at a point. Tangents are consistent (algorithmic) tangents.
struct SmallStrainResponse {
  SymTensor2 stress;  // Cauchy stress [Pa]
  SymTensor4 tangent; // dσ/dε [Pa]
  MaterialState state;
};

struct FiniteStrainResponse {
  Tensor2 first_piola; // P [Pa]
  Tensor4 dP_dF;       // ∂P/∂F [Pa], index order (i,J,k,L): dP_iJ / dF_kL
  MaterialState state;
};

// The stress alone, for callers that need no tangent (explicit steps, energy quadrature).
struct FiniteStrainStress {
  Tensor2 first_piola; // P [Pa]
  MaterialState state;
};

struct LawParameters; // law_parameters.h

class ConstitutiveLaw {
 public:
  virtual ~ConstitutiveLaw() = default;
  virtual std::string name() const = 0;
  // The parameters rebuild_law() makes this law from again, giving the same stresses to the
  // last bit (a law travels between ranks and into checkpoints as its parameters). False for
  // a law that cannot be described by LawParameters.
  virtual bool describe(LawParameters& out) const;

  // Linearised kinematics: total strain ε and temperature change ΔT [K] from the reference.
  virtual SmallStrainResponse small_strain(const SymTensor2& strain, double temperature_change,
                                           const MaterialState& old_state) const = 0;

  // Finite deformation: deformation gradient F (det F > 0, else NumericalFailure).
  virtual FiniteStrainResponse finite_strain(const Tensor2& F, double temperature_change,
                                             const MaterialState& old_state) const = 0;
  // The same P and state without ∂P/∂F. The default calls finite_strain(); a law whose tangent
  // costs several times its stress overrides it (an explicit step evaluates the law once per
  // particle family or quadrature point and step, and never uses the tangent).
  virtual FiniteStrainStress finite_strain_stress(const Tensor2& F, double temperature_change,
                                                  const MaterialState& old_state) const;

  // The stored (recoverable) energy per reference volume [J/m^3] at F after the update from
  // `old_state`, for laws with history whose stored energy is a function of their state (not
  // the path integral ∫P:dF, which counts what plastic flow dissipated, or with a stressed
  // intermediate configuration misses it). nullopt for the others: hyperelastic laws, where
  // the path integral from F = I is the stored energy, and laws with their own formula.
  // Where it has a value, the state's plastic_work is the rest of the work done: an energy
  // account adds it (stored_energy_from_state()).
  virtual std::optional<double> stored_energy_density(const Tensor2& F, double temperature_change,
                                                      const MaterialState& old_state) const;
  // Whether stored_energy_density has a value (it does for every F and state, or for none).
  bool stored_energy_from_state() const;

  // `state` of a point now at deformation gradient F_from, rewritten for a point that carries
  // it on at F_to with the same elastic trial state. A law whose history lives in the
  // intermediate configuration (J2FiniteStrain's C_p⁻¹) must rewrite it, or b^e = F C_p⁻¹ Fᵀ
  // and with it the stress jump by F_to F_from⁻¹; that happens where a state moves between
  // discretisations that see different F at one material point (an F-bar cell's F̄ and a
  // particle family's F).
  // The default, for laws whose state is spatial or small-strain, returns it unchanged.
  virtual MaterialState transferred_state(const MaterialState& state, const Tensor2& F_from,
                                          const Tensor2& F_to) const;

  // Whether finite_strain() uses linearised kinematics (ε = sym F − I, P = σ): then P is the
  // (small-strain) Cauchy stress itself, not P = J σ F⁻ᵀ (stress output).
  virtual bool linearised_kinematics() const { return false; }

  // Share D of the elastic stiffness the point has lost to the law's own damage (a ductile
  // damage law's D(ε̄_p)); 0 for laws without damage [-].
  virtual double stiffness_damage(const MaterialState&) const { return 0.0; }

  // Elastic constants for stable-step estimates, stabilisation and AMG scaling.
  virtual double youngs_modulus() const = 0; // [Pa]
  virtual double poisson_ratio() const = 0;  // [-]
  virtual double density() const = 0;        // [kg/m^3]
  // Longitudinal (P-) wave speed sqrt((λ+2μ)/ρ) [m/s].
  double p_wave_speed() const;
};

} // namespace spinesim::materials

#endif
