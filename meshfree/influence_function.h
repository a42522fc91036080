#ifndef SPINESIM_MESHFREE_INFLUENCE_FUNCTION_H
#define SPINESIM_MESHFREE_INFLUENCE_FUNCTION_H

// Influence functions ω(ξ) of the bond-based family, in the *stretch form* used throughout
// meshfree/: the bond force density is f = c ω(ξ) s n with the bond stretch s = e/ξ, so that
// ω = 1 ("constant") is the classical PMB model of Silling & Askari (2005).
//
// The fractional kernel of Jo & Ha (2021, eqs. 7 and 9) writes the force as
// f = c_α ω_α e with ω_α = 1/ξ^(d+α). Since e = s ξ this is f = c_α (ξ ω_α) s, so its stretch
// form is ω(ξ) = ξ ω_α = ξ^(1−d−α) (Jo & Ha 2021, eq. 21, ω_(α−1)). In 2-D α = −1 gives the PMB
// kernel, in 3-D α = −2.

#include <string>

namespace spinesim::meshfree {

// The names from_name() takes, as a parameter selection (the same in 2-D and 3-D).
inline std::string influence_function_names() {
  return "constant|fractional|gaussian|cubic spline";
}

template <int dim>
class InfluenceFunction {
 public:
  enum class Kind { constant, fractional, gaussian, cubic_spline };

  explicit InfluenceFunction(Kind kind = Kind::constant, double alpha = 0.0);
  // Names: "constant", "fractional", "gaussian", "cubic spline". InvalidInput otherwise,
  // or if α >= 2 for the fractional kernel (the horizon integrals diverge).
  static InfluenceFunction from_name(const std::string& name, double alpha = 0.0);
  static std::string names() { return influence_function_names(); }

  Kind kind() const { return kind_; }
  double alpha() const { return alpha_; }
  std::string name() const;

  // ω(ξ) for a bond of length ξ > 0 in a horizon δ (stretch form, see above) [m^(1-d-α)
  // for the fractional kernel, dimensionless otherwise].
  double operator()(double xi, double delta) const;

  // Radial moment m_n = ∫_0^δ ω(ξ) ξ^n dξ: closed form for constant and fractional kernels,
  // 64-panel Gauss–Legendre for the smooth ones. Every continuum calibration (micromodulus,
  // critical stretch, surface correction) is written in terms of these moments.
  double moment(unsigned int n, double delta) const;

 private:
  Kind kind_;
  double alpha_;
  double exponent_; // fractional: ω = ξ^exponent_, exponent_ = 1 − d − α
};

} // namespace spinesim::meshfree

#endif
