#ifndef SPINESIM_COUPLING_POINT_BINS_H
#define SPINESIM_COUPLING_POINT_BINS_H

// Candidate search for the coupling's geometric queries (cells near flagged cells, ghost cells
// near free particles, MLS stencils of interface nodes): a hash of uniform bins.

#include <deal.II/base/point.h>

#include <array>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace spinesim::coupling {

// Uniform bins of the given size over a point set: candidates within one bin distance.
template <int dim>
class PointBins {
 public:
  PointBins(const std::vector<dealii::Point<dim>>& points, double size)
      : points_(points), size_(size) {
    for (unsigned int i = 0; i < points.size(); ++i)
      bins_[key(points[i])].push_back(i);
  }
  // Whether some point lies within `radius` of x.
  bool any_within(const dealii::Point<dim>& x, double radius) const {
    return !visit_within(x, radius, [](unsigned int) { return false; });
  }
  // Indices of points within `radius` of x.
  std::vector<unsigned int> within(const dealii::Point<dim>& x, double radius) const {
    std::vector<unsigned int> out;
    visit_within(x, radius, [&](unsigned int i) {
      out.push_back(i);
      return true;
    });
    return out;
  }

 private:
  std::array<long, 3> coords(const dealii::Point<dim>& x) const {
    std::array<long, 3> k{{0, 0, 0}};
    for (unsigned int d = 0; d < dim; ++d)
      k[d] = static_cast<long>(std::floor(x[d] / size_));
    return k;
  }
  static long long pack(const std::array<long, 3>& k) {
    return ((k[0] + (1L << 20)) << 42) ^ ((k[1] + (1L << 20)) << 21) ^ (k[2] + (1L << 20));
  }
  long long key(const dealii::Point<dim>& x) const { return pack(coords(x)); }
  // Calls visit(i) for the points within `radius` of x until it returns false; returns
  // whether every call returned true.
  template <class Visit>
  bool visit_within(const dealii::Point<dim>& x, double radius, Visit&& visit) const {
    const std::array<long, 3> k = coords(x);
    const int span = static_cast<int>(std::ceil(radius / size_));
    std::array<long, 3> o{};
    for (o[0] = -span; o[0] <= span; ++o[0])
      for (o[1] = -span; o[1] <= span; ++o[1])
        for (o[2] = (dim == 3 ? -span : 0); o[2] <= (dim == 3 ? span : 0); ++o[2]) {
          const auto it = bins_.find(pack({{k[0] + o[0], k[1] + o[1], k[2] + o[2]}}));
          if (it == bins_.end())
            continue;
          for (const unsigned int i : it->second)
            if (points_[i].distance(x) <= radius && !visit(i))
              return false;
        }
    return true;
  }
  const std::vector<dealii::Point<dim>>& points_;
  double size_;
  std::unordered_map<long long, std::vector<unsigned int>> bins_;
};

} // namespace spinesim::coupling

#endif
