#include "meshfree/spg/essential_boundary.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <Eigen/Sparse>
#include <Eigen/SparseLU>

#include <map>

namespace spinesim::meshfree {

template <int dim>
struct EssentialBoundary<dim>::Component {
  std::map<unsigned int, double> prescribed; // particle → ḡ
  std::vector<unsigned int> nodes;           // B, ascending
  std::vector<int> local;                    // particle → row in B, −1 if free
  // Λ_BF as triplets (row in B, free particle, Ψ_J(X_B)).
  std::vector<unsigned int> bf_row, bf_col;
  std::vector<double> bf_value;
  Eigen::SparseMatrix<double> lambda_bb;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_t; // of Λ_BBᵀ
  bool ready = false;
};

template <int dim>
EssentialBoundary<dim>::EssentialBoundary() {
  for (unsigned int c = 0; c < dim; ++c)
    components_.push_back(std::make_unique<Component>());
}
template <int dim>
EssentialBoundary<dim>::~EssentialBoundary() = default;
template <int dim>
EssentialBoundary<dim>::EssentialBoundary(EssentialBoundary&&) noexcept = default;
template <int dim>
EssentialBoundary<dim>& EssentialBoundary<dim>::operator=(EssentialBoundary&&) noexcept = default;

template <int dim>
void EssentialBoundary<dim>::add(unsigned int particle, unsigned int component, double value) {
  if (component >= dim)
    throw InvalidInput("EssentialBoundary::add", "component " + std::to_string(component),
                       "0 .. dim−1");
  components_[component]->prescribed[particle] = value;
  components_[component]->ready = false;
}

template <int dim>
void EssentialBoundary<dim>::set_value(unsigned int particle, unsigned int component,
                                       double value) {
  auto& p = components_.at(component)->prescribed;
  auto it = p.find(particle);
  if (it == p.end())
    throw InvalidInput("EssentialBoundary::set_value",
                       "particle " + std::to_string(particle) + " is not constrained",
                       "a particle/component given to add()");
  it->second = value;
}

template <int dim>
bool EssentialBoundary<dim>::empty() const {
  return size() == 0;
}

template <int dim>
std::size_t EssentialBoundary<dim>::size() const {
  std::size_t s = 0;
  for (const auto& c : components_)
    s += c->prescribed.size();
  return s;
}

template <int dim>
bool EssentialBoundary<dim>::is_constrained(unsigned int particle, unsigned int component) const {
  return components_.at(component)->prescribed.count(particle) > 0;
}

template <int dim>
void EssentialBoundary<dim>::setup(unsigned int n_particles, const RKShapeFunctions<dim>& rk,
                                   const BondList<dim>& bonds) {
  n_ = n_particles;
  for (unsigned int c = 0; c < dim; ++c) {
    Component& comp = *components_[c];
    comp.nodes.clear();
    comp.local.assign(n_particles, -1);
    for (const auto& [i, g] : comp.prescribed) {
      if (i >= n_particles)
        throw InvalidInput("EssentialBoundary", "particle " + std::to_string(i),
                           "an index below the particle count");
      comp.local[i] = static_cast<int>(comp.nodes.size());
      comp.nodes.push_back(i);
    }
    comp.bf_row.clear();
    comp.bf_col.clear();
    comp.bf_value.clear();
    const int nb = comp.nodes.size();
    if (nb == 0) {
      comp.ready = true;
      continue;
    }
    std::vector<Eigen::Triplet<double>> t;
    for (int r = 0; r < nb; ++r) {
      const unsigned int i = comp.nodes[r];
      t.emplace_back(r, r, rk.self_value[i]);
      for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
        const double psi = rk.value[k];
        if (psi == 0.0)
          return;
        if (comp.local[j] >= 0)
          t.emplace_back(r, comp.local[j], psi);
        else {
          comp.bf_row.push_back(r);
          comp.bf_col.push_back(j);
          comp.bf_value.push_back(psi);
        }
      });
    }
    comp.lambda_bb.resize(nb, nb);
    comp.lambda_bb.setFromTriplets(t.begin(), t.end());
    comp.lambda_bb.makeCompressed();
    comp.lu.compute(comp.lambda_bb);
    Eigen::SparseMatrix<double> tr = comp.lambda_bb.transpose();
    comp.lu_t.compute(tr);
    if (comp.lu.info() != Eigen::Success || comp.lu_t.info() != Eigen::Success)
      throw NumericalFailure("singular boundary transformation matrix Λ_BB (component " +
                                 std::to_string(c) + ", " + std::to_string(nb) + " particles)",
                             "essential boundary of component " + std::to_string(c),
                             "constrain particles that are not all inside one support, or "
                             "increase the dilation");
    comp.ready = true;
  }
}

template <int dim>
void EssentialBoundary<dim>::apply(std::vector<dealii::Tensor<1, dim>>& d,
                                   const std::vector<dealii::Tensor<1, dim>>& d_ref,
                                   const std::vector<dealii::Tensor<1, dim>>& shift,
                                   bool homogeneous) const {
  for (unsigned int c = 0; c < dim; ++c) {
    const Component& comp = *components_[c];
    const int nb = comp.nodes.size();
    if (nb == 0)
      continue;
    if (!comp.ready)
      throw InvalidInput("EssentialBoundary::apply", "constraints changed without setup()",
                         "call setup() after add()");
    Eigen::VectorXd rhs(nb);
    for (int r = 0; r < nb; ++r) {
      const unsigned int i = comp.nodes[r];
      rhs[r] = homogeneous ? 0.0 : comp.prescribed.at(i) - shift[i][c];
    }
    for (std::size_t e = 0; e < comp.bf_row.size(); ++e) {
      const unsigned int j = comp.bf_col[e];
      const double ej = d[j][c] - (homogeneous ? 0.0 : d_ref[j][c]);
      rhs[comp.bf_row[e]] -= comp.bf_value[e] * ej;
    }
    const Eigen::VectorXd x = comp.lu.solve(rhs);
    for (int r = 0; r < nb; ++r) {
      const unsigned int i = comp.nodes[r];
      d[i][c] = x[r] + (homogeneous ? 0.0 : d_ref[i][c]);
    }
  }
}

template <int dim>
void EssentialBoundary<dim>::condense(std::vector<dealii::Tensor<1, dim>>& f) const {
  for (unsigned int c = 0; c < dim; ++c) {
    const Component& comp = *components_[c];
    const int nb = comp.nodes.size();
    if (nb == 0)
      continue;
    Eigen::VectorXd fb(nb);
    for (int r = 0; r < nb; ++r)
      fb[r] = f[comp.nodes[r]][c];
    const Eigen::VectorXd y = comp.lu_t.solve(fb);
    for (std::size_t e = 0; e < comp.bf_row.size(); ++e)
      f[comp.bf_col[e]][c] -= comp.bf_value[e] * y[comp.bf_row[e]];
    for (int r = 0; r < nb; ++r)
      f[comp.nodes[r]][c] = 0.0;
  }
}

template class EssentialBoundary<2>;
template class EssentialBoundary<3>;

} // namespace spinesim::meshfree
