#ifndef SPINESIM_IMPLANTS_TRIANGLE_SOLID_H
#define SPINESIM_IMPLANTS_TRIANGLE_SOLID_H

// A solid bounded by a closed triangulated surface, read from STL (binary or ASCII) through
// CGAL: the soup of triangles is repaired (STL repeats each triangle's corners: duplicate
// points merge, degenerate triangles go), oriented consistently and checked to be closed,
// manifold and free of self-intersections, then oriented outward. Point-in-solid queries go
// through CGAL's Side_of_triangle_mesh (ray casting over an AABB tree, exact predicates).
// CGAL stays inside triangle_solid.cc.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::implants {

class TriangleSolid {
 public:
  // Reads `file`; `where` names the parameter for errors. Bad input (unreadable, empty, not
  // closed, non-manifold, self-intersecting) throws InvalidInput naming the file and what was
  // found. Coordinates are multiplied by `scale` (e.g. 1e-3 for a file in mm).
  TriangleSolid(const std::string& file, const std::string& where, double scale);
  // From points and triangles (counter-clockwise seen from outside), checked the same way.
  TriangleSolid(const std::vector<dealii::Point<3>>& points,
                const std::vector<std::array<unsigned int, 3>>& triangles,
                const std::string& where);
  ~TriangleSolid();
  TriangleSolid(TriangleSolid&&) noexcept;
  TriangleSolid& operator=(TriangleSolid&&) noexcept;

  // Points strictly inside or on the surface count as inside.
  bool inside(const dealii::Point<3>& x) const;
  // Signed distance from x to the surface, negative inside [m]; `normal` gets the outward unit
  // normal there: along x minus its nearest surface point, or the nearest triangle's normal
  // when x lies on the surface (an AABB tree of the triangles, built on the first call).
  double signed_distance(const dealii::Point<3>& x, dealii::Tensor<1, 3>& normal) const;
  double volume() const; // enclosed volume [m^3]
  double area() const;   // surface area [m^2]
  std::size_t n_triangles() const;
  const std::vector<dealii::Point<3>>& vertices() const { return vertices_; }
  // The triangles as indices into vertices(), counter-clockwise seen from outside.
  std::vector<std::array<unsigned int, 3>> triangles() const;
  // Moves every vertex by x -> f(x) (a rigid placement), rebuilding the queries.
  template <typename F>
  void transform(const F& f) {
    for (auto& v : vertices_)
      v = f(v);
    rebuild();
  }

  // Writes binary STL. Throws std::runtime_error on an I/O failure.
  static void write_stl(const std::string& file, const std::vector<dealii::Point<3>>& points,
                        const std::vector<std::array<unsigned int, 3>>& triangles);

 private:
  struct Impl;
  void build(std::vector<dealii::Point<3>> points, std::vector<std::vector<std::size_t>> polygons,
             const std::string& file, const std::string& where);
  void rebuild();
  std::unique_ptr<Impl> impl_;
  std::vector<dealii::Point<3>> vertices_;
};

} // namespace spinesim::implants

#endif
