#include "fem/materials/j2_plasticity.h"

#include "fem/materials/material_models.h"

#include "fem/materials/j2_return_mapping.h"
#include "fem/materials/tensor_tools.h"

#include <utility>

namespace spinesim::materials {

J2Plasticity::J2Plasticity(double E, double nu, double rho, double alpha,
                           const IsotropicHardening& hardening)
    : E_(E), nu_(nu), rho_(rho), alpha_(alpha), hardening_(hardening) {
  validate_elastic_constants("j2_plasticity", E, nu, rho, alpha);
  K_ = bulk_modulus(E, nu);
  mu_ = shear_modulus(E, nu);
}

SmallStrainResponse J2Plasticity::small_strain(const SymTensor2& strain, double dT,
                                               const MaterialState& old_state) const {
  return respond(strain, dT, old_state, true);
}

SmallStrainResponse J2Plasticity::respond(const SymTensor2& strain, double dT,
                                          const MaterialState& old_state, bool with_tangent) const {
  check_finite(strain, "strain", *this);
  const SymTensor2 eps_tr =
      strain - old_state.plastic_strain - alpha_ * dT * dealii::unit_symmetric_tensor<3>();
  const J2ReturnResult rm = j2_radial_return(eps_tr, old_state.equivalent_plastic_strain, K_, mu_,
                                             hardening_, law_name, with_tangent);
  SmallStrainResponse r;
  r.stress = rm.stress;
  r.tangent = rm.tangent;
  r.state = old_state;
  if (rm.plastic) {
    r.state.plastic_strain += rm.plastic_strain_increment;
    r.state.equivalent_plastic_strain += rm.delta_gamma;
    r.state.plastic_work += rm.delta_gamma * rm.flow_stress;
  }
  return r;
}

FiniteStrainResponse J2Plasticity::finite_strain(const Tensor2& F, double dT,
                                                 const MaterialState& old_state) const {
  checked_determinant(F, *this);
  return as_linearised_finite_strain(respond(linearised_strain(F), dT, old_state, true));
}

FiniteStrainStress J2Plasticity::finite_strain_stress(const Tensor2& F, double dT,
                                                      const MaterialState& old_state) const {
  checked_determinant(F, *this);
  SmallStrainResponse r = respond(linearised_strain(F), dT, old_state, false);
  return {Tensor2(r.stress), std::move(r.state)};
}

bool J2Plasticity::describe(LawParameters& out) const {
  out = LawParameters::elastic(name(), E_, nu_, rho_, alpha_).with_hardening(hardening_);
  return true;
}

SPINESIM_REGISTER_MATERIAL_MODEL(j2_plasticity, "j2_plasticity",
                                 "small-strain von Mises, radial return.", true,
                                 [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
                                   return std::make_unique<J2Plasticity>(
                                       p.youngs_modulus, p.poisson_ratio, p.density,
                                       p.thermal_expansion,
                                       IsotropicHardening(p.yield_stress, p.hardening_modulus,
                                                          p.saturation_stress,
                                                          p.saturation_exponent));
                                 })

double J2Plasticity::stored_energy_density(const SymTensor2& stress) const {
  const double p = dealii::trace(stress) / 3.0;
  const auto s = dealii::deviator(stress);
  return s * s / (4.0 * mu_) + p * p / (2.0 * K_);
}

std::optional<double> J2Plasticity::stored_energy_density(const Tensor2& F, double dT,
                                                          const MaterialState& old_state) const {
  return stored_energy_density(
      dealii::symmetrize(finite_strain_stress(F, dT, old_state).first_piola));
}

} // namespace spinesim::materials
