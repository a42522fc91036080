#include "fem/materials/j2_damage.h"

#include "base/exceptions.h"
#include "fem/materials/material_models.h"
#include "fem/materials/tensor_tools.h"

#include <cmath>
#include <sstream>

namespace spinesim::materials {

void DamageCurve::validate() const {
  if (!(onset_plastic_strain >= 0) || !std::isfinite(onset_plastic_strain))
    throw InvalidInput("Damage onset plastic strain", std::to_string(onset_plastic_strain),
                       "a finite plastic strain >= 0 [-]");
  if (!(softening_strain > 0) || !std::isfinite(softening_strain))
    throw InvalidInput("Damage softening strain", std::to_string(softening_strain),
                       "a finite strain > 0 [-]");
  if (!(maximum_damage >= 0 && maximum_damage < 1))
    throw InvalidInput("Maximum damage", std::to_string(maximum_damage),
                       "0 <= D_max < 1 (a failed point keeps 1 - D_max of its stiffness)");
}

void DamageCurve::declare(dealii::ParameterHandler& prm, const DamageCurve& defaults,
                          const std::string& solid) {
  using dealii::Patterns::Double;
  const auto text = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  prm.declare_entry("Damage onset plastic strain", text(defaults.onset_plastic_strain), Double(0),
                    "j2_damage: equivalent plastic strain at which " + solid +
                        " starts to soften [-]: D = D_max (1 - exp(-(eps_bar_p - onset) / "
                        "softening)), sigma = (1 - D) sigma_effective.");
  prm.declare_entry("Damage softening strain", text(defaults.softening_strain), Double(0),
                    "j2_damage: plastic strain past the onset over which D rises to 63 % of "
                    "D_max [-], > 0.");
  prm.declare_entry("Maximum damage", text(defaults.maximum_damage), Double(0, 1),
                    "j2_damage: residual damage D_max of " + solid +
                        " [-], 0 <= D_max < 1: a failed point keeps 1 - D_max of its stiffness "
                        "and strength.");
}

DamageCurve DamageCurve::parse(const dealii::ParameterHandler& prm) {
  DamageCurve d;
  d.onset_plastic_strain = prm.get_double("Damage onset plastic strain");
  d.softening_strain = prm.get_double("Damage softening strain");
  d.maximum_damage = prm.get_double("Maximum damage");
  return d;
}

double DamageCurve::damage(double e) const {
  const double x = e - onset_plastic_strain;
  return x > 0 ? maximum_damage * (1.0 - std::exp(-x / softening_strain)) : 0.0;
}

double DamageCurve::slope(double e) const {
  const double x = e - onset_plastic_strain;
  return x > 0 ? maximum_damage / softening_strain * std::exp(-x / softening_strain) : 0.0;
}

J2Damage::J2Damage(double E, double nu, double rho, double alpha,
                   const IsotropicHardening& hardening, const DamageCurve& damage, bool secant)
    : effective_(E, nu, rho, alpha, hardening), damage_(damage), secant_(secant) {
  damage_.validate();
  mu_ = shear_modulus(E, nu);
}

SmallStrainResponse J2Damage::small_strain(const SymTensor2& strain, double dT,
                                           const MaterialState& old_state) const {
  // The effective (undamaged) response: J2Plasticity's radial return and tangent.
  const SmallStrainResponse e = effective_.small_strain(strain, dT, old_state);
  SmallStrainResponse r;
  r.state = e.state;
  const double ep = e.state.equivalent_plastic_strain;
  const double delta_gamma = ep - old_state.equivalent_plastic_strain;
  const double D = damage_.damage(ep);
  r.stress = (1.0 - D) * e.stress;
  r.tangent = (1.0 - D) * e.tangent;
  if (delta_gamma > 0) {
    r.state.plastic_work =
        old_state.plastic_work + (1.0 - D) * (e.state.plastic_work - old_state.plastic_work);
    const double dD = damage_.slope(ep);
    if (dD > 0 && !secant_) {
      // n̂: the unit deviatoric flow direction; the returned deviator is parallel to the trial
      // one, and a plastic step has a non-zero deviator.
      const SymTensor2 s = dealii::deviator(e.stress);
      const SymTensor2 n = s / s.norm();
      const double dgamma_factor = 2.0 * mu_ * std::sqrt(1.5) / (3.0 * mu_ + hardening().slope(ep));
      r.tangent -= (dD * dgamma_factor) * dealii::outer_product(e.stress, n);
    }
  }
  return r;
}

FiniteStrainResponse J2Damage::finite_strain(const Tensor2& F, double dT,
                                             const MaterialState& old_state) const {
  checked_determinant(F, *this);
  return as_linearised_finite_strain(small_strain(linearised_strain(F), dT, old_state));
}

FiniteStrainStress J2Damage::finite_strain_stress(const Tensor2& F, double dT,
                                                  const MaterialState& old_state) const {
  // small_strain without the tangent: the effective stress scaled by 1 − D(ε̄_p).
  checked_determinant(F, *this); // failures name this law, as finite_strain's do
  const FiniteStrainStress e = effective_.finite_strain_stress(F, dT, old_state);
  const double ep = e.state.equivalent_plastic_strain;
  const double D = damage_.damage(ep);
  FiniteStrainStress r{(1.0 - D) * e.first_piola, e.state};
  if (ep - old_state.equivalent_plastic_strain > 0)
    r.state.plastic_work =
        old_state.plastic_work + (1.0 - D) * (e.state.plastic_work - old_state.plastic_work);
  return r;
}

std::optional<double> J2Damage::stored_energy_density(const Tensor2& F, double dT,
                                                      const MaterialState& old_state) const {
  const FiniteStrainStress e = effective_.finite_strain_stress(F, dT, old_state);
  const double D = damage_.damage(e.state.equivalent_plastic_strain);
  return (1.0 - D) * effective_.stored_energy_density(dealii::symmetrize(e.first_piola));
}

bool J2Damage::describe(LawParameters& out) const {
  effective_.describe(out);
  out.model = name();
  out.damage_onset_plastic_strain = damage_.onset_plastic_strain;
  out.damage_softening_strain = damage_.softening_strain;
  out.maximum_damage = damage_.maximum_damage;
  out.secant_tangent = secant_;
  return true;
}

SPINESIM_REGISTER_MATERIAL_MODEL(
    j2_damage, "j2_damage",
    "small-strain von Mises with ductile damage D(eps_bar_p) on the effective stress "
    "(softening after the Damage onset plastic strain).",
    true, [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
      return std::make_unique<J2Damage>(
          p.youngs_modulus, p.poisson_ratio, p.density, p.thermal_expansion,
          IsotropicHardening(p.yield_stress, p.hardening_modulus, p.saturation_stress,
                             p.saturation_exponent),
          DamageCurve{p.damage_onset_plastic_strain, p.damage_softening_strain, p.maximum_damage},
          p.secant_tangent);
    })

} // namespace spinesim::materials
