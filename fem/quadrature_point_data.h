#ifndef SPINESIM_FEM_QUADRATURE_POINT_DATA_H
#define SPINESIM_FEM_QUADRATURE_POINT_DATA_H

// What one quadrature point of the mechanics remembers, and its flat layout in checkpoints.

#include "fem/materials/constitutive_law.h"

namespace spinesim::fem {

struct QuadraturePointData {
  materials::MaterialState state;
  materials::SymTensor2 cauchy_stress; // σ [Pa]
  materials::SymTensor2 strain;        // ε (small) or Green-Lagrange E (finite) [-]
  materials::Tensor2 work_stress;      // σ (small) or P (finite) [Pa], conjugate to:
  materials::Tensor2 deformation;      // ε (small) or F (finite) [-]
  double work_density = 0;             // ∫ stress power dt per reference volume [J/m^3]
};

// Doubles per point in a checkpoint: plastic strain and elastic b (symmetric), equivalent
// plastic strain, plastic work, σ and strain (symmetric), work stress and deformation (full),
// work density.
constexpr unsigned int quadrature_point_doubles = 6 + 6 + 1 + 1 + 6 + 6 + 9 + 9 + 1;

// Writes / reads quadrature_point_doubles values in the order above.
void pack(const QuadraturePointData& d, double* out);
void unpack(const double* in, QuadraturePointData& d);

} // namespace spinesim::fem

#endif
