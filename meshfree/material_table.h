#ifndef SPINESIM_MESHFREE_MATERIAL_TABLE_H
#define SPINESIM_MESHFREE_MATERIAL_TABLE_H

// The constitutive laws of a particle set that holds several materials (a coupled run whose
// particles come from cells of different laws: bone of CT density, an implant). A particle's
// ParticleSet::material_id is its index here. Entries are only ever appended, in an order
// every rank reproduces (the coupling adds them in the all-gathered order of its particle
// records), so an index means the same law on every rank and in a checkpoint.
//
// Across a bond between two materials the methods take the harmonic mean of the two
// micromoduli (two springs in series, each half a bond long) and the smaller critical
// stretch (the weaker side breaks the bond). Both are symmetric in i and j to the last bit,
// so the two ends of a bond see one stiffness and break together.

#include "fem/materials/constitutive_law.h"

#include <cmath>
#include <memory>
#include <vector>

namespace spinesim::meshfree {

class MaterialTable {
 public:
  struct Entry {
    std::shared_ptr<const materials::ConstitutiveLaw> law;
    double youngs_modulus = 0, poisson_ratio = 0, density = 0; // [Pa], [-], [kg/m^3]
    double p_modulus = 0;                                      // λ + 2μ [Pa]
    double p_wave_speed = 0;                                   // sqrt((λ + 2μ)/ρ) [m/s]
  };

  // Appends `law` and returns its index.
  unsigned int add(std::shared_ptr<const materials::ConstitutiveLaw> law) {
    Entry e;
    e.youngs_modulus = law->youngs_modulus();
    e.poisson_ratio = law->poisson_ratio();
    e.density = law->density();
    const double nu = e.poisson_ratio;
    e.p_modulus = e.youngs_modulus * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    e.p_wave_speed = law->p_wave_speed();
    e.law = std::move(law);
    entries_.push_back(std::move(e));
    return static_cast<unsigned int>(entries_.size() - 1);
  }
  void clear() { entries_.clear(); }

  unsigned int size() const { return static_cast<unsigned int>(entries_.size()); }
  bool empty() const { return entries_.empty(); }
  const Entry& operator[](unsigned int m) const { return entries_[m]; }
  const materials::ConstitutiveLaw& law(unsigned int m) const { return *entries_[m].law; }
  const std::shared_ptr<const materials::ConstitutiveLaw>& law_pointer(unsigned int m) const {
    return entries_[m].law;
  }

  // Whether any law's stored energy is a function of its state (plastic work to account).
  bool any_stored_energy_from_state() const {
    for (const auto& e : entries_)
      if (e.law->stored_energy_from_state())
        return true;
    return false;
  }

 private:
  std::vector<Entry> entries_;
};

// Two springs in series, each half a bond long: 2ab/(a+b); symmetric in a and b to the bit
// (IEEE + and * commute).
inline double series_mean(double a, double b) {
  return 2 * a * b / (a + b);
}

} // namespace spinesim::meshfree

#endif
