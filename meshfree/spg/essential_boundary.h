#ifndef SPINESIM_MESHFREE_SPG_ESSENTIAL_BOUNDARY_H
#define SPINESIM_MESHFREE_SPG_ESSENTIAL_BOUNDARY_H

// Essential boundary conditions for RK approximations, which are not interpolating
// (u^h(X_I) = Σ_J Ψ_J(X_I) d_J ≠ d_I), by the MIXED TRANSFORMATION METHOD (Chen & Wang 2000;
// as in Wu, Park & Chen 2015, with Λ_IJ = Ψ_J(X_I) restricted to the constrained particles):
//
//   for each component c, with B the particles constrained in c and F the rest,
//       Λ_BB e_B + Λ_BF e_F = ḡ_B − s_B        (the physical value u^h(X_B) = ḡ)
//   so the constrained coefficients are slaves, e_B = Λ_BB⁻¹ (ḡ_B − s_B − Λ_BF e_F), and the
//   generalised force on the free ones is the chain rule  f_F ← f_F − Λ_BFᵀ Λ_BB⁻ᵀ f_B.
//
// e are coefficient increments (d − d_ref) and s a per-particle shift, so the same code serves
// the total Lagrangian (d_ref = 0, s = 0) and the updated Lagrangian configuration (see
// SPGSolver). The condensed equilibrium f_F = 0 is the exact constrained (KKT) condition, so
// static solutions are exact; in dynamics the lumped mass of the slave coefficients is
// neglected (they follow the masters). Λ_BB is sparse and factorised once per kernel update
// (Eigen SparseLU).

#include "meshfree/bond_list.h"
#include "meshfree/spg/rk_shape_functions.h"

#include <deal.II/base/tensor.h>

#include <memory>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class EssentialBoundary {
 public:
  EssentialBoundary();
  ~EssentialBoundary();
  EssentialBoundary(EssentialBoundary&&) noexcept;
  EssentialBoundary& operator=(EssentialBoundary&&) noexcept;

  // Constrains component c of the physical displacement at particle i to `value` [m].
  void add(unsigned int particle, unsigned int component, double value);
  // Changes the prescribed value of an existing constraint (e.g. time-dependent loading).
  void set_value(unsigned int particle, unsigned int component, double value);
  bool empty() const;
  std::size_t size() const;
  bool is_constrained(unsigned int particle, unsigned int component) const;

  // Factorises Λ_BB per component. NumericalFailure if singular (names the component).
  void setup(unsigned int n_particles, const RKShapeFunctions<dim>& rk, const BondList<dim>& bonds);

  // d_B so that Σ_J Ψ_J(X_B)(d_J − d_ref,J) = ḡ_B − shift_B (homogeneous: = 0, for velocities).
  void apply(std::vector<dealii::Tensor<1, dim>>& d,
             const std::vector<dealii::Tensor<1, dim>>& d_ref,
             const std::vector<dealii::Tensor<1, dim>>& shift, bool homogeneous) const;
  // f_F ← f_F − Λ_BFᵀ Λ_BB⁻ᵀ f_B, then f_B = 0.
  void condense(std::vector<dealii::Tensor<1, dim>>& f) const;

 private:
  struct Component;
  std::vector<std::unique_ptr<Component>> components_;
  unsigned int n_ = 0;
};

} // namespace spinesim::meshfree

#endif
