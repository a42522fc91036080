#include "meshfree/influence_function.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::meshfree {

template <int dim>
InfluenceFunction<dim>::InfluenceFunction(Kind kind, double alpha)
    : kind_(kind), alpha_(alpha), exponent_(1.0 - dim - alpha) {
  if (kind_ == Kind::fractional && !(alpha_ < 2.0))
    throw InvalidInput("Influence function / Alpha", "alpha = " + std::to_string(alpha_),
                       "alpha < 2 (the horizon integral of the fractional kernel diverges "
                       "for alpha >= 2)");
}

template <int dim>
InfluenceFunction<dim> InfluenceFunction<dim>::from_name(const std::string& name, double alpha) {
  if (name == "constant")
    return InfluenceFunction(Kind::constant, alpha);
  if (name == "fractional")
    return InfluenceFunction(Kind::fractional, alpha);
  if (name == "gaussian")
    return InfluenceFunction(Kind::gaussian, alpha);
  if (name == "cubic spline")
    return InfluenceFunction(Kind::cubic_spline, alpha);
  throw InvalidInput("Influence function", "unknown influence function '" + name + "'", names());
}

template <int dim>
std::string InfluenceFunction<dim>::name() const {
  switch (kind_) {
  case Kind::constant:
    return "constant";
  case Kind::fractional:
    return "fractional";
  case Kind::gaussian:
    return "gaussian";
  case Kind::cubic_spline:
    return "cubic spline";
  }
  return "";
}

template <int dim>
double InfluenceFunction<dim>::operator()(double xi, double delta) const {
  switch (kind_) {
  case Kind::constant:
    return 1.0;
  case Kind::fractional:
    return std::pow(xi, exponent_);
  case Kind::gaussian:
    return std::exp(-(xi * xi) / (delta * delta));
  case Kind::cubic_spline: {
    // Cubic B-spline with support δ, scaled so that ω(0) = 1.
    const double q = xi / delta;
    if (q <= 0.5)
      return 1.0 - 6.0 * q * q + 6.0 * q * q * q;
    if (q <= 1.0)
      return 2.0 * (1.0 - q) * (1.0 - q) * (1.0 - q);
    return 0.0;
  }
  }
  return 0.0;
}

template <int dim>
double InfluenceFunction<dim>::moment(unsigned int n, double delta) const {
  switch (kind_) {
  case Kind::constant:
    return std::pow(delta, n + 1.0) / (n + 1.0);
  case Kind::fractional: {
    const double p = n + exponent_ + 1.0;
    if (!(p > 0.0))
      throw InvalidInput("Influence function / Alpha", "alpha = " + std::to_string(alpha_),
                         "a smaller alpha: the moment of order " + std::to_string(n) +
                             " of the fractional kernel diverges");
    return std::pow(delta, p) / p;
  }
  default: {
    // Smooth kernels: composite 5-point Gauss–Legendre, exact to round-off for these
    // polynomials and far below any tolerance for the Gaussian.
    static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                                0.9061798459386640};
    static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                0.4786286704993665, 0.2369268850561891};
    const unsigned int panels = 64;
    const double hp = delta / panels;
    double sum = 0;
    for (unsigned int p = 0; p < panels; ++p)
      for (unsigned int q = 0; q < 5; ++q) {
        const double xi = (p + 0.5 * (x[q] + 1.0)) * hp;
        sum += 0.5 * hp * w[q] * (*this)(xi, delta) * std::pow(xi, n);
      }
    return sum;
  }
  }
}

template class InfluenceFunction<2>;
template class InfluenceFunction<3>;

} // namespace spinesim::meshfree
