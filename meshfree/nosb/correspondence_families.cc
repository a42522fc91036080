#include "meshfree/nosb/correspondence_families.h"

#include "meshfree/bond_loop.h"

#include <deal.II/base/symmetric_tensor.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace spinesim::meshfree {

namespace {

// λ_max/λ_min of a symmetric positive semi-definite dim×dim tensor; +inf when singular.
template <int dim>
double condition_number(const dealii::Tensor<2, dim>& K) {
  // Jacobi: robust for (nearly) isotropic K, where the closed-form 2x2/3x3 eigenvalues take
  // the square root of a slightly negative discriminant.
  const auto ev =
      dealii::eigenvectors(dealii::symmetrize(K), dealii::SymmetricTensorEigenvectorMethod::jacobi);
  double lmax = ev[0].first, lmin = ev[0].first;
  for (unsigned int d = 1; d < dim; ++d) {
    lmax = std::max(lmax, ev[d].first);
    lmin = std::min(lmin, ev[d].first);
  }
  if (!(lmin > 0.0) || !std::isfinite(lmax))
    return std::numeric_limits<double>::infinity();
  return lmax / lmin;
}

} // namespace

template <int dim>
std::vector<unsigned int> CorrespondenceFamilies<dim>::build(const ParticleSet<dim>& particles,
                                                             const BondList<dim>& bonds,
                                                             const Options& options) {
  using Vec = dealii::Tensor<1, dim>;
  using Mat = dealii::Tensor<2, dim>;
  const unsigned int n = particles.size();
  const auto& V = particles.volumes();
  std::vector<std::uint8_t> was_failed = failed_;
  was_failed.resize(n, 0);
  failed_.assign(n, 0);
  condition_.assign(n, std::numeric_limits<double>::infinity());
  centre_.clear();
  weight_.clear();
  history_.clear();
  offsets_.assign(1, 0);
  node_.clear();
  gradient_.clear();
  fallbacks_ = 0;

  auto bond_weight = [&](std::size_t k) {
    return bonds.influence[k] * bonds.volume_factor(k) * V[bonds.neighbor[k]];
  };
  // Adds the family of centre i over the bond subset `members` with inverse shape tensor Kinv.
  auto add_family = [&](unsigned int i, double w, std::size_t history,
                        const std::vector<std::size_t>& members, const Mat& Kinv) {
    centre_.push_back(i);
    weight_.push_back(w);
    history_.push_back(history);
    const std::size_t centre_slot = node_.size();
    node_.push_back(i);
    gradient_.emplace_back();
    Vec sum;
    for (const std::size_t k : members) {
      const Vec g = bond_weight(k) * (Kinv * bonds.xi[k]);
      node_.push_back(bonds.neighbor[k]);
      gradient_.push_back(g);
      sum += g;
    }
    gradient_[centre_slot] = -sum;
    offsets_.push_back(node_.size());
  };

  std::vector<std::size_t> members, lens;
  std::vector<unsigned int> newly_failed;
  for (unsigned int i = 0; i < n; ++i) {
    members.clear();
    Mat K;
    double all_weight = 0;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
      if (bonds.broken[k])
        return;
      members.push_back(k);
      K += bond_weight(k) * dealii::outer_product(bonds.xi[k], bonds.xi[k]);
      all_weight += bond_weight(k);
    });
    condition_[i] =
        members.size() >= dim ? condition_number(K) : std::numeric_limits<double>::infinity();
    if (!(condition_[i] <= options.max_condition_number)) {
      failed_[i] = 1;
      if (!was_failed[i])
        newly_failed.push_back(i);
      continue;
    }
    const Mat Kinv = dealii::invert(K);
    if (options.kind == Kind::particle) {
      add_family(i, V[i], i, members, Kinv);
      continue;
    }
    for (const std::size_t kb : members) {
      lens.clear();
      Mat Kb;
      for (const std::size_t k : members)
        if ((bonds.xi[k] - bonds.xi[kb]).norm() <= bonds.horizon) {
          lens.push_back(k);
          Kb += bond_weight(k) * dealii::outer_product(bonds.xi[k], bonds.xi[k]);
        }
      const double w = V[i] * bond_weight(kb) / all_weight;
      if (lens.size() >= dim && condition_number(Kb) <= options.max_condition_number)
        add_family(i, w, kb, lens, dealii::invert(Kb));
      else {
        ++fallbacks_;
        add_family(i, w, kb, members, Kinv);
      }
    }
  }
  return newly_failed;
}

template <int dim>
unsigned int CorrespondenceFamilies<dim>::n_failed() const {
  return static_cast<unsigned int>(std::count(failed_.begin(), failed_.end(), 1));
}

template <int dim>
dealii::Tensor<2, dim> CorrespondenceFamilies<dim>::deformation_gradient(
    unsigned int e, const std::vector<dealii::Tensor<1, dim>>& u) const {
  dealii::Tensor<2, dim> F = dealii::unit_symmetric_tensor<dim>();
  for (std::size_t q = begin(e); q < end(e); ++q)
    F += dealii::outer_product(u[node_[q]], gradient_[q]);
  return F;
}

template class CorrespondenceFamilies<2>;
template class CorrespondenceFamilies<3>;

} // namespace spinesim::meshfree
