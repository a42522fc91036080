#include "fem/ct/ct_cell_laws.h"

#include "base/exceptions.h"
#include "fem/ct/density_modulus_law.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_damage.h"
#include "fem/materials/j2_plasticity.h"
#include "fem/materials/linear_elastic.h"

#include <algorithm>
#include <cmath>

namespace spinesim::fem {

CtCellLaws::CtCellLaws(const CtModel& model, const Options& options)
    : laws_(std::make_shared<std::vector<LawPointer>>()),
      yield_(std::make_shared<std::vector<double>>()) {
  const std::size_t n = model.cell_modulus.size();
  if (model.mesh.cell_density.size() != n)
    throw InvalidInput("CT cell laws", "density and modulus lists differ in length",
                       "a model from build_ct_model");
  if (!(options.hardening_ratio >= 0 && options.hardening_ratio < 1))
    throw InvalidInput("Hardening ratio", std::to_string(options.hardening_ratio), "0 <= H/E < 1");
  if (!(options.minimum_density > 0))
    throw InvalidInput("Minimum density", std::to_string(options.minimum_density),
                       "a positive density [g/cm^3]");
  const bool plastic = options.kind == Kind::j2_plasticity;
  std::unique_ptr<DensityModulusLaw> yield_law;
  if (plastic) {
    yield_law =
        std::make_unique<DensityModulusLaw>(options.yield_law, 1.0, options.minimum_density, 1.0);
    if (!yield_law->has_yield_stress())
      throw InvalidInput("Yield law", "'" + options.yield_law + "' defines no yield stress",
                         "kopperdahl2002");
  }
  // Label moduli already sit in cell_modulus; only nu and the kind depend on the label here.
  laws_->resize(n);
  yield_->assign(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    const int label = c < model.cell_label.size() ? model.cell_label[c] : 0;
    const auto nu_it = options.label_poisson_ratio.find(label);
    const double nu =
        nu_it != options.label_poisson_ratio.end() ? nu_it->second : model.poisson_ratio;
    const double E = model.cell_modulus[c];
    const double rho = model.mesh.cell_density[c];
    if (!std::isfinite(E) || !(E > 0))
      throw NumericalFailure("CT cell modulus", "coarse cell " + std::to_string(c),
                             "E = " + std::to_string(E) + " Pa; check the density floors");
    const double mass_density = 1000.0 * std::max(rho, options.minimum_density);
    if (plastic && !options.elastic_labels.count(label)) {
      const double sy = yield_law->yield_stress(rho);
      (*yield_)[c] = sy;
      const materials::IsotropicHardening hardening(sy, options.hardening_ratio * E);
      if (options.damage)
        (*laws_)[c] = std::make_shared<materials::J2Damage>(E, nu, mass_density, 0.0, hardening,
                                                            *options.damage);
      else
        (*laws_)[c] =
            std::make_shared<materials::J2Plasticity>(E, nu, mass_density, 0.0, hardening);
      ++n_plastic_;
    } else {
      (*laws_)[c] = std::make_shared<materials::LinearElastic>(E, nu, mass_density);
    }
  }
}

CtCellLaws::Function CtCellLaws::function() const {
  const auto laws = laws_;
  return [laws](const dealii::Triangulation<3>::active_cell_iterator& cell) -> LawPointer {
    return laws->at(cell->id().get_coarse_cell_id());
  };
}

} // namespace spinesim::fem
