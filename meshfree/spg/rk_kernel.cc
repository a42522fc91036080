#include "meshfree/spg/rk_kernel.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::meshfree {

template <int dim>
RKKernel<dim>::RKKernel(Type type, Support support) : type_(type), support_(support) {}

template <int dim>
RKKernel<dim> RKKernel<dim>::from_names(const std::string& type, const std::string& support) {
  Type t;
  if (type == "cubic_bspline")
    t = Type::cubic_bspline;
  else if (type == "quartic")
    t = Type::quartic;
  else
    throw InvalidInput("Kernel", "unknown kernel '" + type + "'", type_names());
  Support s;
  if (support == "spherical")
    s = Support::spherical;
  else if (support == "cubic")
    s = Support::cubic;
  else
    throw InvalidInput("Support shape", "unknown support '" + support + "'", support_names());
  return RKKernel(t, s);
}

template <int dim>
double RKKernel<dim>::profile(double r) const {
  if (r >= 1.0)
    return 0.0;
  if (type_ == Type::cubic_bspline) {
    if (r <= 0.5)
      return 1.0 - 6.0 * r * r + 6.0 * r * r * r;
    const double s = 1.0 - r;
    return 2.0 * s * s * s;
  }
  const double s = 1.0 - r * r;
  return s * s * s * s;
}

template <int dim>
double RKKernel<dim>::profile_derivative(double r) const {
  if (r >= 1.0)
    return 0.0;
  if (type_ == Type::cubic_bspline) {
    if (r <= 0.5)
      return -12.0 * r + 18.0 * r * r;
    const double s = 1.0 - r;
    return -6.0 * s * s;
  }
  const double s = 1.0 - r * r;
  return -8.0 * r * s * s * s;
}

template <int dim>
double RKKernel<dim>::value(const dealii::Tensor<1, dim>& z, double a) const {
  if (support_ == Support::spherical)
    return profile(z.norm() / a);
  double w = 1.0;
  for (unsigned int k = 0; k < dim; ++k)
    w *= profile(std::abs(z[k]) / a);
  return w;
}

template <int dim>
double RKKernel<dim>::value_and_gradient(const dealii::Tensor<1, dim>& z, double a,
                                         dealii::Tensor<1, dim>& gradient) const {
  gradient = 0;
  if (support_ == Support::spherical) {
    const double d = z.norm();
    const double r = d / a;
    if (r >= 1.0)
      return 0.0;
    // dφ/dr → 0 as r → 0 for both profiles, so the gradient at z = 0 is zero.
    if (d > 0.0)
      gradient = (profile_derivative(r) / (a * d)) * z;
    return profile(r);
  }
  double f[dim], df[dim];
  for (unsigned int k = 0; k < dim; ++k) {
    const double r = std::abs(z[k]) / a;
    f[k] = profile(r);
    df[k] = profile_derivative(r) / a * (z[k] < 0 ? -1.0 : 1.0);
  }
  double w = 1.0;
  for (unsigned int k = 0; k < dim; ++k)
    w *= f[k];
  for (unsigned int k = 0; k < dim; ++k) {
    double g = df[k];
    for (unsigned int l = 0; l < dim; ++l)
      if (l != k)
        g *= f[l];
    gradient[k] = g;
  }
  return w;
}

template <int dim>
double RKKernel<dim>::search_radius(double a) const {
  return support_ == Support::spherical ? a : a * std::sqrt(double(dim));
}

template class RKKernel<2>;
template class RKKernel<3>;

} // namespace spinesim::meshfree
