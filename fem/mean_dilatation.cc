#include "fem/mean_dilatation.h"

namespace spinesim::fem {

using namespace dealii;

template <int dim>
void MeanDilatation<dim>::reinit(const FEValues<dim>& fe_values,
                                 const std::vector<unsigned int>& component) {
  fe_values_ = &fe_values;
  component_ = component;
  const unsigned int n = component.size(), nq = fe_values.n_quadrature_points;
  volume_ = 0;
  for (unsigned int q = 0; q < nq; ++q)
    volume_ += fe_values.JxW(q);
  mean_grad_.assign(n, 0.0);
  for (unsigned int i = 0; i < n; ++i) {
    double s = 0;
    for (unsigned int q = 0; q < nq; ++q)
      s += fe_values.shape_grad(i, q)[component[i]] * fe_values.JxW(q);
    mean_grad_[i] = s / volume_;
  }
}

template <int dim>
double MeanDilatation<dim>::average_dilatation(const std::vector<Tensor<2, dim>>& grads) const {
  double s = 0;
  for (unsigned int q = 0; q < grads.size(); ++q)
    s += trace(grads[q]) * fe_values_->JxW(q);
  return s / volume_;
}

template <int dim>
void MeanDilatation<dim>::project(materials::Tensor2& H, double average_dilatation) {
  const double shift = (average_dilatation - trace(H)) / 3.0;
  for (unsigned int d = 0; d < 3; ++d)
    H[d][d] += shift;
}

template class MeanDilatation<2>;
template class MeanDilatation<3>;

} // namespace spinesim::fem
