#include "fem/f_bar.h"

#include <cmath>

namespace spinesim::fem {

template <int dim>
bool FBar<dim>::reinit(const dealii::FEValues<dim>& fe_values,
                       const std::vector<unsigned int>& component,
                       const std::vector<dealii::Tensor<2, dim>>& grads, unsigned int& worst) {
  fe_values_ = &fe_values;
  component_ = &component;
  const unsigned int nq = fe_values.n_quadrature_points, n = fe_values.dofs_per_cell;
  F_.resize(nq);
  F_inverse_.resize(nq);
  J_.resize(nq);
  alpha_.resize(nq);
  mean_dJ_.assign(n, 0.0);
  pressure_sum_ = 0;
  double volume = 0, deformed = 0;
  worst = 0;
  bool bad = false; // a point with J <= 0 or J not finite (NaN compares false)
  for (unsigned int q = 0; q < nq; ++q) {
    F_[q] = grads[q];
    for (unsigned int d = 0; d < dim; ++d)
      F_[q][d][d] += 1.0;
    J_[q] = dealii::determinant(F_[q]);
    if (!bad && !(J_[q] > 0 && std::isfinite(J_[q]))) {
      bad = true;
      worst = q;
    } else if (!bad && J_[q] < J_[worst]) {
      worst = q;
    }
    volume += fe_values.JxW(q);
    deformed += J_[q] * fe_values.JxW(q);
  }
  mean_J_ = deformed / volume;
  if (bad || !(mean_J_ > 0))
    return false;
  for (unsigned int q = 0; q < nq; ++q) {
    F_inverse_[q] = dealii::invert(F_[q]);
    alpha_[q] = std::pow(mean_J_ / J_[q], 1.0 / dim);
    const double w = J_[q] * fe_values.JxW(q) / volume;
    for (unsigned int i = 0; i < n; ++i) {
      const dealii::Tensor<1, dim>& g = fe_values.shape_grad(i, q);
      const unsigned int c = component[i];
      double s = 0;
      for (unsigned int k = 0; k < dim; ++k)
        s += F_inverse_[q][k][c] * g[k];
      mean_dJ_[i] += w * s;
    }
  }
  return true;
}

template <int dim>
materials::Tensor2 FBar<dim>::modified_gradient(unsigned int q) const {
  materials::Tensor2 H;
  for (unsigned int i = 0; i < dim; ++i)
    for (unsigned int j = 0; j < dim; ++j)
      H[i][j] = alpha_[q] * F_[q][i][j] - (i == j ? 1.0 : 0.0);
  return H;
}

template <int dim>
void FBar<dim>::add_point_forces(unsigned int q, const materials::Tensor2& P,
                                 std::vector<double>& force) {
  const double JxW = fe_values_->JxW(q), alpha = alpha_[q];
  double PF = 0; // P̄_d : F
  for (unsigned int i = 0; i < dim; ++i)
    for (unsigned int j = 0; j < dim; ++j)
      PF += P[i][j] * F_[q][i][j];
  const double p = alpha / dim * PF;
  pressure_sum_ += p * JxW;
  for (unsigned int i = 0; i < force.size(); ++i) {
    const dealii::Tensor<1, dim>& g = fe_values_->shape_grad(i, q);
    const unsigned int c = (*component_)[i];
    double s = 0;
    for (unsigned int k = 0; k < dim; ++k)
      s += (alpha * P[c][k] - p * F_inverse_[q][k][c]) * g[k];
    force[i] += s * JxW;
  }
}

template <int dim>
void FBar<dim>::finish_cell(std::vector<double>& force) {
  for (unsigned int i = 0; i < force.size(); ++i)
    force[i] += pressure_sum_ * mean_dJ_[i] / mean_J_;
  pressure_sum_ = 0;
}

template class FBar<2>;
template class FBar<3>;

} // namespace spinesim::fem
