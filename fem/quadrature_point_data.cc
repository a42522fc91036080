#include "fem/quadrature_point_data.h"

namespace spinesim::fem {

using materials::SymTensor2;
using materials::Tensor2;

void pack(const QuadraturePointData& d, double* out) {
  auto sym = [&](const SymTensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = i; j < 3; ++j)
        *out++ = t[i][j];
  };
  auto full = [&](const Tensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        *out++ = t[i][j];
  };
  sym(d.state.plastic_strain);
  sym(d.state.elastic_left_cauchy_green);
  *out++ = d.state.equivalent_plastic_strain;
  *out++ = d.state.plastic_work;
  sym(d.cauchy_stress);
  sym(d.strain);
  full(d.work_stress);
  full(d.deformation);
  *out++ = d.work_density;
}

void unpack(const double* in, QuadraturePointData& d) {
  auto sym = [&](SymTensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = i; j < 3; ++j)
        t[i][j] = *in++;
  };
  auto full = [&](Tensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        t[i][j] = *in++;
  };
  sym(d.state.plastic_strain);
  sym(d.state.elastic_left_cauchy_green);
  d.state.equivalent_plastic_strain = *in++;
  d.state.plastic_work = *in++;
  sym(d.cauchy_stress);
  sym(d.strain);
  full(d.work_stress);
  full(d.deformation);
  d.work_density = *in++;
}

} // namespace spinesim::fem
