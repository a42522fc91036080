#include "fem/materials/constitutive_law.h"

#include <cmath>
#include <utility>

namespace spinesim::materials {

FiniteStrainStress ConstitutiveLaw::finite_strain_stress(const Tensor2& F, double dT,
                                                         const MaterialState& old_state) const {
  FiniteStrainResponse r = finite_strain(F, dT, old_state);
  return {r.first_piola, std::move(r.state)};
}

bool ConstitutiveLaw::describe(LawParameters&) const {
  return false;
}

std::optional<double> ConstitutiveLaw::stored_energy_density(const Tensor2&, double,
                                                             const MaterialState&) const {
  return std::nullopt;
}

bool ConstitutiveLaw::stored_energy_from_state() const {
  // At F = I from the initial state: one cheap update, no virtual flag to keep in step.
  return stored_energy_density(Tensor2(dealii::unit_symmetric_tensor<3>()), 0.0, MaterialState())
      .has_value();
}

MaterialState ConstitutiveLaw::transferred_state(const MaterialState& state, const Tensor2&,
                                                 const Tensor2&) const {
  return state;
}

double ConstitutiveLaw::p_wave_speed() const {
  const double E = youngs_modulus(), nu = poisson_ratio();
  const double lambda_plus_2mu = E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
  return std::sqrt(lambda_plus_2mu / density());
}

} // namespace spinesim::materials
