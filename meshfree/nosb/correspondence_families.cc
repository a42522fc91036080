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
  const unsigned int n = particles.size();
  const auto& V = particles.volumes();
  std::vector<std::uint8_t> was_failed = failed_;
  was_failed.resize(n, 0);
  failed_.assign(n, 0);
  condition_.assign(n, std::numeric_limits<double>::infinity());
  centre_.clear();
  weight_.clear();
  history_.clear();
  mask_begin_.clear();
  inverse_shape_.clear();
  mask_.clear();
  family_begin_.assign(n + 1, 0);
  moment_.clear();
  kind_ = options.kind;
  fallbacks_ = 0;

  // The bonds as the families will read them.
  bond_offsets_.assign(bonds.offsets.begin(), bonds.offsets.begin() + n + 1);
  bond_node_ = bonds.neighbor;
  std::vector<unsigned int> bond_centre(bonds.n_bonds()); // read by this build only
  for (unsigned int i = 0; i < n; ++i)
    std::fill(bond_centre.begin() + bonds.begin(i), bond_centre.begin() + bonds.end(i), i);
  // ω V_n per bond (a local for the build) and the stored ω V_n ξ.
  std::vector<double> bond_weight(bonds.n_bonds());
  bond_moment_.resize(bonds.n_bonds());
  for (std::size_t k = 0; k < bonds.n_bonds(); ++k) {
    bond_weight[k] = bonds.influence[k] * bonds.volume_factor(k) * V[bonds.neighbor[k]];
    bond_moment_[k] = bond_weight[k] * bonds.xi[k];
  }
  // Their transpose: per particle, the bonds that end on it, ascending.
  incoming_offsets_.assign(n + 1, 0);
  for (std::size_t k = 0; k < bond_node_.size(); ++k)
    ++incoming_offsets_[bond_node_[k] + 1];
  for (unsigned int m = 0; m < n; ++m)
    incoming_offsets_[m + 1] += incoming_offsets_[m];
  incoming_.resize(bond_node_.size());
  {
    std::vector<std::size_t> next(incoming_offsets_.begin(), incoming_offsets_.end() - 1);
    for (std::size_t k = 0; k < bond_node_.size(); ++k)
      incoming_[next[bond_node_[k]]++] = k;
  }

  // Adds a family of centre i: weight w, history index, K⁻¹ and the slots of its members.
  std::vector<std::uint64_t> words;
  auto add_family = [&](unsigned int i, double w, std::size_t history,
                        const std::vector<std::size_t>& slots, const Mat& Kinv) {
    const std::size_t n_words = (bonds.end(i) - bonds.begin(i) + 63) / 64;
    words.assign(n_words, 0);
    Vec moment;
    for (const std::size_t s : slots) {
      words[s / 64] |= std::uint64_t(1) << (s % 64);
      moment += bond_moment_[bonds.begin(i) + s];
    }
    moment_.push_back(moment);
    centre_.push_back(i);
    weight_.push_back(w);
    history_.push_back(history);
    inverse_shape_.push_back(Kinv);
    mask_begin_.push_back(mask_.size());
    mask_.insert(mask_.end(), words.begin(), words.end());
  };

  std::vector<std::size_t> members, lens; // slots of i's bonds
  std::vector<unsigned int> newly_failed;
  for (unsigned int i = 0; i < n; ++i) {
    family_begin_[i] = static_cast<unsigned int>(centre_.size());
    const std::size_t b0 = bonds.begin(i);
    members.clear();
    Mat K;
    double all_weight = 0;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
      if (bonds.broken[k])
        return;
      members.push_back(k - b0);
      K += bond_weight[k] * dealii::outer_product(bonds.xi[k], bonds.xi[k]);
      all_weight += bond_weight[k];
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
    for (const std::size_t sb : members) {
      const std::size_t kb = b0 + sb;
      lens.clear();
      Mat Kb;
      for (const std::size_t s : members) {
        const std::size_t k = b0 + s;
        if ((bonds.xi[k] - bonds.xi[kb]).norm() <= bonds.horizon) {
          lens.push_back(s);
          Kb += bond_weight[k] * dealii::outer_product(bonds.xi[k], bonds.xi[k]);
        }
      }
      const double w = V[i] * bond_weight[kb] / all_weight;
      if (lens.size() >= dim && condition_number(Kb) <= options.max_condition_number)
        add_family(i, w, kb, lens, dealii::invert(Kb));
      else {
        ++fallbacks_;
        add_family(i, w, kb, members, Kinv);
      }
    }
  }
  family_begin_[n] = static_cast<unsigned int>(centre_.size());
  // Particle families: the gather reads, in incoming order, the family of the bond's centre
  // that holds it (none when broken or the centre failed) and ω_k V_n ξ_k, so that each bond
  // costs one scattered read (that family's Q) as a stored gradient did.
  incoming_family_.clear();
  incoming_moment_.clear();
  if (options.kind == Kind::particle) {
    incoming_family_.resize(incoming_.size(), no_family);
    incoming_moment_.resize(incoming_.size());
    for (std::size_t t = 0; t < incoming_.size(); ++t) {
      const std::size_t k = incoming_[t];
      const unsigned int i = bond_centre[k], e = family_begin_[i];
      if (family_begin_[i + 1] > e && holds(e, k - bond_offsets_[i])) {
        incoming_family_[t] = e;
        incoming_moment_[t] = bond_moment_[k];
      }
    }
  }
  // Particle families gather from the copies above; the bond indices were for this build.
  if (options.kind == Kind::particle)
    std::vector<std::size_t>().swap(incoming_);
  return newly_failed;
}

template <int dim>
unsigned int CorrespondenceFamilies<dim>::n_failed() const {
  return static_cast<unsigned int>(std::count(failed_.begin(), failed_.end(), 1));
}

template <int dim>
void CorrespondenceFamilies<dim>::expand(unsigned int e, std::vector<unsigned int>& nodes,
                                         std::vector<Vec>& gradients) const {
  const unsigned int i = centre_[e];
  const std::size_t b0 = bond_offsets_[i], nb = bond_offsets_[i + 1] - b0;
  nodes.assign(1, i);
  gradients.assign(1, Vec());
  Vec sum;
  for_each_member(e, nb, [&](std::size_t s) {
    const Vec g = inverse_shape_[e] * bond_moment_[b0 + s];
    nodes.push_back(bond_node_[b0 + s]);
    gradients.push_back(g);
    sum += g;
  });
  gradients[0] = -sum;
}

template <int dim>
dealii::Tensor<2, dim>
CorrespondenceFamilies<dim>::deformation_gradient(unsigned int e, const std::vector<Vec>& u) const {
  // F = I + Σ_n (u_n − u_c) ⊗ G_n = I + [Σ_n u_n ⊗ ω_n V_n ξ_n − u_c ⊗ m_e] K⁻ᵀ.
  const unsigned int i = centre_[e];
  const std::size_t b0 = bond_offsets_[i], nb = bond_offsets_[i + 1] - b0;
  Mat A = -dealii::outer_product(u[i], moment_[e]);
  for_each_member(e, nb, [&](std::size_t s) {
    const Vec& un = u[bond_node_[b0 + s]];
    const Vec& m = bond_moment_[b0 + s];
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int c = 0; c < dim; ++c)
        A[a][c] += un[a] * m[c];
  });
  Mat F = A * dealii::transpose(inverse_shape_[e]);
  for (unsigned int d = 0; d < dim; ++d)
    F[d][d] += 1.0;
  return F;
}

// The two loops over every member of every bond-associated family (about 60 of each particle's
// ~120 families in 3-D) are most of a NOSB force pass: compiled also for x86-64-v3 (AVX2) and
// x86-64-v4 (AVX-512), chosen at load time by the CPU. Their sums run in the same order in
// every version and this file is compiled without contraction into fused multiply-adds
// (meshfree/CMakeLists.txt), so each gives the same results to the bit.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SPINESIM_FAMILY_KERNEL                                                                     \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define SPINESIM_FAMILY_KERNEL
#endif

template <int dim>
SPINESIM_FAMILY_KERNEL void CorrespondenceFamilies<dim>::particle_deformation_gradients(
    unsigned int i, const std::vector<Vec>& u, Mat* F) const {
  // Each product u_n ⊗ ω_n V_n ξ_n is formed once for i's families and rounded once, as
  // deformation_gradient(e, u) forms it, and each family sums its members in that order.
  const std::size_t b0 = bond_offsets_[i], nb = bond_offsets_[i + 1] - b0;
  thread_local std::vector<Mat> products;
  products.resize(nb);
  for (std::size_t s = 0; s < nb; ++s) {
    const Vec& un = u[bond_node_[b0 + s]];
    const Vec& m = bond_moment_[b0 + s];
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int c = 0; c < dim; ++c)
        products[s][a][c] = un[a] * m[c];
  }
  for (unsigned int e = family_begin_[i]; e < family_begin_[i + 1]; ++e) {
    Mat A = -dealii::outer_product(u[i], moment_[e]);
    for_each_member(e, nb, [&](std::size_t s) {
      const Mat& p = products[s];
      for (unsigned int a = 0; a < dim; ++a)
        for (unsigned int c = 0; c < dim; ++c)
          A[a][c] += p[a][c];
    });
    Mat Fe = A * dealii::transpose(inverse_shape_[e]);
    for (unsigned int d = 0; d < dim; ++d)
      Fe[d][d] += 1.0;
    F[e - family_begin_[i]] = Fe;
  }
}

template <int dim>
SPINESIM_FAMILY_KERNEL dealii::Tensor<1, dim>
CorrespondenceFamilies<dim>::gather_bond_forces(unsigned int i, const std::vector<Mat>& P) const {
  const std::size_t b0 = bond_offsets_[i], nb = bond_offsets_[i + 1] - b0;
  thread_local std::vector<Mat> sum;
  sum.assign(nb, Mat());
  Vec fi;
  for (unsigned int e = family_begin_[i]; e < family_begin_[i + 1]; ++e) {
    const Mat q = weight_[e] * (P[e] * inverse_shape_[e]);
    fi += q * moment_[e];
    for_each_member(e, nb, [&](std::size_t slot) { sum[slot] += q; });
  }
  for (std::size_t s = 0; s < nb; ++s)
    bond_force_[b0 + s] = sum[s] * bond_moment_[b0 + s];
  return fi;
}

template <int dim>
void CorrespondenceFamilies<dim>::gather_forces(const std::vector<Mat>& P, std::vector<Vec>& f,
                                                long parallel_threshold) const {
  const long n = static_cast<long>(family_begin_.size()) - 1;
  // Q_e = w_e P_e K_e⁻¹: −w_e P_e G_n = −Q_e ω_n V_n ξ_n on a member n, and on the centre
  // −w_e P_e G_c = Q_e Σ_n ω_n V_n ξ_n = Q_e m_e (m_e: the family's first moment, from build).
  if (kind_ == Kind::particle) {
    // One family per particle: per bond i→m, the family of i holds it or the bond is broken.
    const long n_fam = n_families();
    q_.resize(n_fam);
    parallel_for_rethrow(n_fam, parallel_threshold,
                         [&](long e) { q_[e] = weight_[e] * (P[e] * inverse_shape_[e]); });
    parallel_for_rethrow(n, parallel_threshold, [&](long m) {
      Vec fm;
      if (family_begin_[m + 1] > family_begin_[m])
        fm = q_[family_begin_[m]] * moment_[family_begin_[m]];
      for (std::size_t t = incoming_offsets_[m]; t < incoming_offsets_[m + 1]; ++t)
        if (incoming_family_[t] != no_family)
          fm -= q_[incoming_family_[t]] * incoming_moment_[t];
      f[m] = fm;
    });
    return;
  }
  // Bond-associated: per particle i, its centre force Σ_e Q_e m_e, and per bond k = i→n
  // t_k = [Σ_e Q_e] ω_k V_n ξ_k over the families of i that hold it (about half of them);
  // then each particle takes away the t of the bonds ending on it, in bond order.
  bond_force_.resize(bond_moment_.size());
  parallel_for_rethrow(n, parallel_threshold,
                       [&](long i) { f[i] = gather_bond_forces(static_cast<unsigned int>(i), P); });
  parallel_for_rethrow(n, parallel_threshold, [&](long m) {
    for (std::size_t t = incoming_offsets_[m]; t < incoming_offsets_[m + 1]; ++t)
      f[m] -= bond_force_[incoming_[t]];
  });
}

template <int dim>
std::size_t CorrespondenceFamilies<dim>::memory_bytes() const {
  return (bond_offsets_.capacity() + incoming_offsets_.capacity() + incoming_.capacity() +
          history_.capacity() + mask_begin_.capacity()) *
             sizeof(std::size_t) +
         (bond_node_.capacity() + centre_.capacity() + family_begin_.capacity()) *
             sizeof(unsigned int) +
         bond_moment_.capacity() * sizeof(Vec) +
         (weight_.capacity() + condition_.capacity()) * sizeof(double) +
         (inverse_shape_.capacity() + q_.capacity()) * sizeof(Mat) +
         (bond_force_.capacity() + moment_.capacity() + incoming_moment_.capacity()) * sizeof(Vec) +
         incoming_family_.capacity() * sizeof(unsigned int) +
         mask_.capacity() * sizeof(std::uint64_t) + failed_.capacity();
}

template class CorrespondenceFamilies<2>;
template class CorrespondenceFamilies<3>;

} // namespace spinesim::meshfree
