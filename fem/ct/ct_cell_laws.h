#ifndef SPINESIM_FEM_CT_CT_CELL_LAWS_H
#define SPINESIM_FEM_CT_CT_CELL_LAWS_H

// Per-cell constitutive laws of a CT model, for MechanicsSolver::set_cell_laws: every coarse
// cell gets its own law with the modulus of CtModel::cell_modulus (density law with floors,
// or the label modulus for e.g. PMMA caps), so a refined or partitioned mesh keeps the
// density map (children inherit the law of their coarse cell).
//   linear_elastic: E(rho), nu, rho.
//   j2_plasticity:  small-strain J2 with E(rho) and the yield stress sigma_y(rho) of a
//                   density-yield law (kopperdahl2002: 37.4 rho^1.39 MPa), linear hardening
//                   H = hardening_ratio * E. J2 is tension-compression symmetric: the
//                   compressive yield stress is used for both (axial compression scenes).
//                   With Options::damage, J2Damage: the same, softening past the curve's
//                   onset (a true peak of the force).
// Labels listed in elastic_labels (PMMA caps) stay linear elastic in either kind. The mass
// density of the law is 1000 max(rho, minimum density) kg/m^3 (laws need rho > 0; the raw
// density stays in CtModel for mass sums).

#include "fem/ct/ct_model.h"
#include "fem/materials/constitutive_law.h"
#include "fem/materials/j2_damage.h"

#include <deal.II/grid/tria.h>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace spinesim::fem {

class CtCellLaws {
 public:
  using LawPointer = std::shared_ptr<const materials::ConstitutiveLaw>;
  // Same signature as MechanicsSolver<3>::CellLawFunction.
  using Function = std::function<LawPointer(const dealii::Triangulation<3>::active_cell_iterator&)>;

  enum class Kind { linear_elastic, j2_plasticity };

  struct Options {
    Kind kind = Kind::linear_elastic;
    std::map<int, double> label_poisson_ratio; // label -> nu (else CtModel::poisson_ratio)
    std::set<int> elastic_labels;              // kept linear elastic in the j2 kind
    std::string yield_law = "kopperdahl2002";  // density -> yield stress (j2 kind)
    double hardening_ratio = 0.0;              // H / E [-] (j2 kind)
    double minimum_density = 1e-3;             // [g/cm^3] floor for the law's mass density
    // j2 kind: with a damage curve the bone softens past it (materials::J2Damage).
    std::optional<materials::DamageCurve> damage;
  };

  // InvalidInput for a yield law without a yield relation or out-of-range options.
  CtCellLaws(const CtModel& model, const Options& options);

  std::size_t size() const { return laws_->size(); }
  // The law of coarse cell `c`.
  const LawPointer& law(std::size_t c) const { return laws_->at(c); }
  template <class CellIterator>
  const LawPointer& cell_law(const CellIterator& cell) const {
    return law(cell->id().get_coarse_cell_id());
  }
  // [Pa] yield stress of coarse cell `c` (0 for elastic cells).
  double yield_stress(std::size_t c) const { return yield_->at(c); }
  unsigned int n_plastic_cells() const { return n_plastic_; }
  // For MechanicsSolver<3>::set_cell_laws; keeps the laws alive on its own.
  Function function() const;

 private:
  std::shared_ptr<std::vector<LawPointer>> laws_;
  std::shared_ptr<std::vector<double>> yield_;
  unsigned int n_plastic_ = 0;
};

} // namespace spinesim::fem

#endif
