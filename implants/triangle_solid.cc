#include "implants/triangle_solid.h"

#include "base/exceptions.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Polygon_mesh_processing/compute_normal.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <filesystem>
#include <mutex>

namespace spinesim::implants {

namespace triangle_solid {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalPoint = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<CgalPoint>;
using Side = CGAL::Side_of_triangle_mesh<Mesh, Kernel>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
namespace PMP = CGAL::Polygon_mesh_processing;
} // namespace triangle_solid

using namespace triangle_solid;

struct TriangleSolid::Impl {
  Mesh mesh;
  // Holds a reference to `mesh`: rebuilt whenever the points move.
  std::unique_ptr<Side> side;
  // For distances, built on first use (and dropped when the points move); the mutex makes the
  // first use safe from several threads.
  mutable std::unique_ptr<Tree> tree;
  mutable std::mutex tree_mutex;
};

TriangleSolid::TriangleSolid(const std::string& file, const std::string& where, double scale) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw InvalidInput(where, file + ": no such file", "an STL file (binary or ASCII)");
  std::vector<CgalPoint> points;
  std::vector<std::vector<std::size_t>> polygons;
  bool ok = false;
  try {
    ok = CGAL::IO::read_STL(file, points, polygons, CGAL::parameters::verbose(false));
  } catch (const std::exception& e) {
    throw InvalidInput(where, file + ": not a readable STL file (" + e.what() + ")",
                       "an STL file (binary or ASCII)");
  }
  if (!ok || polygons.empty())
    throw InvalidInput(where,
                       file + (ok ? ": not a readable STL file (no triangles in it)"
                                  : ": not a readable STL file (truncated, or neither binary "
                                    "nor ASCII STL)"),
                       "a closed triangulated surface in STL (binary or ASCII)");
  std::vector<dealii::Point<3>> p(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (unsigned int d = 0; d < 3; ++d)
      p[i][d] = scale * points[i][d];
    if (!std::isfinite(p[i].norm()))
      throw InvalidInput(where, file + ": vertex " + std::to_string(i) + " is not finite",
                         "finite coordinates");
  }
  build(std::move(p), std::move(polygons), file, where);
}

TriangleSolid::TriangleSolid(const std::vector<dealii::Point<3>>& points,
                             const std::vector<std::array<unsigned int, 3>>& triangles,
                             const std::string& where) {
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(triangles.size());
  for (const auto& t : triangles)
    polygons.push_back({t[0], t[1], t[2]});
  build(points, std::move(polygons), "triangles", where);
}

TriangleSolid::~TriangleSolid() = default;
TriangleSolid::TriangleSolid(TriangleSolid&&) noexcept = default;
TriangleSolid& TriangleSolid::operator=(TriangleSolid&&) noexcept = default;

void TriangleSolid::build(std::vector<dealii::Point<3>> points,
                          std::vector<std::vector<std::size_t>> polygons, const std::string& file,
                          const std::string& where) {
  const std::string allowed = "a closed, manifold, not self-intersecting triangulated surface";
  std::vector<CgalPoint> soup(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    soup[i] = CgalPoint(points[i][0], points[i][1], points[i][2]);
  // STL repeats the corners of every triangle: merge them, drop degenerate triangles.
  PMP::repair_polygon_soup(soup, polygons);
  if (polygons.empty())
    throw InvalidInput(where, file + ": every triangle is degenerate", allowed);
  if (!PMP::orient_polygon_soup(soup, polygons))
    throw InvalidInput(where,
                       file + ": the surface is not manifold (an edge or vertex shared by more "
                              "than one sheet)",
                       allowed);
  impl_ = std::make_unique<Impl>();
  Mesh& mesh = impl_->mesh;
  PMP::polygon_soup_to_polygon_mesh(soup, polygons, mesh);
  std::size_t border = 0;
  for (const auto h : mesh.halfedges())
    border += mesh.is_border(h);
  if (border > 0 || !CGAL::is_closed(mesh))
    throw InvalidInput(where,
                       file + ": the surface is not closed (" + std::to_string(border) +
                           " edges border a hole)",
                       allowed);
  // Zero-area slivers (collinear corners, common in CAD exports) would count as
  // self-intersections: collapse them first, keeping the surface closed.
  const std::size_t faces_before = mesh.number_of_faces();
  PMP::remove_degenerate_faces(mesh);
  mesh.collect_garbage();
  if (!CGAL::is_closed(mesh) || mesh.number_of_faces() == 0)
    throw InvalidInput(where,
                       file + ": removing its " +
                           std::to_string(faces_before - mesh.number_of_faces()) +
                           " zero-area triangles opened the surface",
                       allowed);
  if (PMP::does_self_intersect(mesh))
    throw InvalidInput(where, file + ": the surface intersects itself", allowed);
  // Outward normals (a file may list its triangles clockwise), so that the volume is positive.
  PMP::orient_to_bound_a_volume(mesh);
  vertices_.resize(mesh.number_of_vertices());
  for (const auto v : mesh.vertices()) {
    const CgalPoint& q = mesh.point(v);
    vertices_[v.idx()] = dealii::Point<3>(q.x(), q.y(), q.z());
  }
  impl_->side = std::make_unique<Side>(mesh);
  if (!(volume() > 0))
    throw InvalidInput(where, file + ": the surface encloses no volume", allowed);
}

void TriangleSolid::rebuild() {
  Mesh& mesh = impl_->mesh;
  for (const auto v : mesh.vertices()) {
    const dealii::Point<3>& q = vertices_[v.idx()];
    mesh.point(v) = CgalPoint(q[0], q[1], q[2]);
  }
  impl_->side = std::make_unique<Side>(mesh);
  impl_->tree.reset();
}

bool TriangleSolid::inside(const dealii::Point<3>& x) const {
  return (*impl_->side)(CgalPoint(x[0], x[1], x[2])) != CGAL::ON_UNBOUNDED_SIDE;
}

double TriangleSolid::signed_distance(const dealii::Point<3>& x,
                                      dealii::Tensor<1, 3>& normal) const {
  const Mesh& mesh = impl_->mesh;
  {
    std::lock_guard<std::mutex> lock(impl_->tree_mutex);
    if (!impl_->tree) {
      impl_->tree = std::make_unique<Tree>(faces(mesh).first, faces(mesh).second, mesh);
      impl_->tree->accelerate_distance_queries();
    }
  }
  const CgalPoint q(x[0], x[1], x[2]);
  const auto [nearest, face] = impl_->tree->closest_point_and_primitive(q);
  const dealii::Point<3> c(nearest.x(), nearest.y(), nearest.z());
  const double d = x.distance(c);
  const bool in = inside(x);
  if (d > 1e-12 * std::max(1.0, x.norm())) {
    normal = (in ? c - x : x - c) / d;
  } else {
    const auto n = PMP::compute_face_normal(face, mesh);
    normal = dealii::Tensor<1, 3>(
        {CGAL::to_double(n.x()), CGAL::to_double(n.y()), CGAL::to_double(n.z())});
  }
  return in ? -d : d;
}

double TriangleSolid::volume() const {
  return CGAL::to_double(PMP::volume(impl_->mesh));
}

double TriangleSolid::area() const {
  return CGAL::to_double(PMP::area(impl_->mesh));
}

std::vector<std::array<unsigned int, 3>> TriangleSolid::triangles() const {
  const Mesh& mesh = impl_->mesh;
  std::vector<std::array<unsigned int, 3>> t;
  t.reserve(mesh.number_of_faces());
  for (const auto f : mesh.faces()) {
    std::array<unsigned int, 3> tri{};
    unsigned int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      if (k < 3)
        tri[k++] = v.idx();
    t.push_back(tri);
  }
  return t;
}

std::size_t TriangleSolid::n_triangles() const {
  return impl_->mesh.number_of_faces();
}

void TriangleSolid::write_stl(const std::string& file, const std::vector<dealii::Point<3>>& points,
                              const std::vector<std::array<unsigned int, 3>>& triangles) {
  std::vector<CgalPoint> p(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    p[i] = CgalPoint(points[i][0], points[i][1], points[i][2]);
  std::vector<std::array<std::size_t, 3>> t(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i)
    t[i] = {{triangles[i][0], triangles[i][1], triangles[i][2]}};
  if (!CGAL::IO::write_STL(file, p, t, CGAL::parameters::use_binary_mode(true)))
    throw std::runtime_error("cannot write " + file);
}

} // namespace spinesim::implants
