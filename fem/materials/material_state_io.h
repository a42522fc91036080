#ifndef SPINESIM_FEM_MATERIALS_MATERIAL_STATE_IO_H
#define SPINESIM_FEM_MATERIALS_MATERIAL_STATE_IO_H

// A material state as a flat array of numbers, for checkpoints and exchange between ranks:
// plastic strain ε_p (6, upper triangle), elastic left Cauchy-Green b^e (6), ε̄_p, w_p, D_f.

#include "fem/materials/constitutive_law.h"

#include <array>
#include <cmath>
#include <string>

namespace spinesim::materials {

constexpr unsigned int material_state_doubles = 15;

// Whether s is the state of untouched material (a new family or particle starts from it, so a
// checkpoint need not write it).
inline bool is_virgin(const MaterialState& s) {
  const MaterialState virgin;
  return s.equivalent_plastic_strain == 0 && s.plastic_work == 0 && s.fracture_damage == 0 &&
         s.plastic_strain == virgin.plastic_strain &&
         s.elastic_left_cauchy_green == virgin.elastic_left_cauchy_green;
}

inline std::array<double, material_state_doubles> pack_state(const MaterialState& s) {
  std::array<double, material_state_doubles> v{};
  unsigned int n = 0;
  for (unsigned int a = 0; a < 3; ++a)
    for (unsigned int b = a; b < 3; ++b) {
      v[n] = s.plastic_strain[a][b];
      v[n + 6] = s.elastic_left_cauchy_green[a][b];
      ++n;
    }
  v[12] = s.equivalent_plastic_strain;
  v[13] = s.plastic_work;
  v[14] = s.fracture_damage;
  return v;
}

inline MaterialState unpack_state(const std::array<double, material_state_doubles>& v) {
  MaterialState s;
  unsigned int n = 0;
  for (unsigned int a = 0; a < 3; ++a)
    for (unsigned int b = a; b < 3; ++b) {
      s.plastic_strain[a][b] = v[n];
      s.elastic_left_cauchy_green[a][b] = v[n + 6];
      ++n;
    }
  s.equivalent_plastic_strain = v[12];
  s.plastic_work = v[13];
  s.fracture_damage = v[14];
  return s;
}

// What makes a state read from a file one no law can have written, or an empty string: every
// number finite, eps_bar_p >= 0, 0 <= D_f <= 1 (a checkpoint is a file from outside).
inline std::string inadmissible_state(const std::array<double, material_state_doubles>& v) {
  for (unsigned int k = 0; k < material_state_doubles; ++k)
    if (!std::isfinite(v[k]))
      return "a non-finite number (entry " + std::to_string(k) + " of " +
             std::to_string(material_state_doubles) + ")";
  if (v[12] < 0)
    return "a negative equivalent plastic strain";
  if (v[14] < 0 || v[14] > 1)
    return "a fracture damage outside [0, 1]";
  return {};
}

} // namespace spinesim::materials

#endif
