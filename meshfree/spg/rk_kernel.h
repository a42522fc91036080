#ifndef SPINESIM_MESHFREE_SPG_RK_KERNEL_H
#define SPINESIM_MESHFREE_SPG_RK_KERNEL_H

// Kernel (weight) functions of the reproducing-kernel approximation, w_a(X − X_J) with support
// size a = dilation × spacing. The normalisation constant C_d of Wu, Park & Chen (2015) is dropped:
// the RK correction M⁻¹ cancels any constant factor, so Ψ does not depend on it.
//
//  * cubic B-spline (SPG; Wu, Park & Chen 2015), r = |z|/a:
//        w = 1 − 6r² + 6r³ (r ≤ ½),  2(1 − r)³ (½ < r ≤ 1),  0 beyond;
//  * quartic (LSMFM, Kwon & Youn 2005):  w = (1 − r²)⁴ (r ≤ 1), 0 beyond (constant √(4/π) dropped).
//
// Support shape: spherical (r = |z|/a) or cubic, the tensor product w(z) = Π_k w(|z_k|/a)
// (a box of half-width a; neighbours must then be searched out to a√dim).

#include <deal.II/base/tensor.h>

#include <string>

namespace spinesim::meshfree {

template <int dim>
class RKKernel {
 public:
  enum class Type { cubic_bspline, quartic };
  enum class Support { spherical, cubic };

  RKKernel(Type type = Type::cubic_bspline, Support support = Support::spherical);
  // Names "cubic_bspline" | "quartic" and "spherical" | "cubic"; InvalidInput otherwise.
  static RKKernel from_names(const std::string& type, const std::string& support);
  static std::string type_names() { return "cubic_bspline|quartic"; }
  static std::string support_names() { return "spherical|cubic"; }

  Type type() const { return type_; }
  Support support() const { return support_; }

  // One-dimensional profile φ(r) and dφ/dr for r >= 0.
  double profile(double r) const;
  double profile_derivative(double r) const;

  // w(z; a) and ∂w/∂z for z = X − X_J [m]; a [m] the support size.
  double value(const dealii::Tensor<1, dim>& z, double a) const;
  double value_and_gradient(const dealii::Tensor<1, dim>& z, double a,
                            dealii::Tensor<1, dim>& gradient) const;

  // Largest |z| with w(z) != 0: a (spherical) or a√dim (cubic) — the neighbour search radius.
  double search_radius(double a) const;

 private:
  Type type_;
  Support support_;
};

} // namespace spinesim::meshfree

#endif
