#include "implants/screw_tessellation.h"

#include "implants/stl_screw.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace spinesim::implants {

Tessellation tessellate(const PedicleScrew& screw, unsigned int rays,
                        unsigned int rings_per_pitch) {
  constexpr double pi = 3.14159265358979323846;
  const auto& g = screw.geometry();
  // Ring positions in s: the head's top and the entry plane, then the shaft at a uniform step,
  // with the start of the tip and the end.
  std::vector<double> s_rings;
  if (g.head_length > 0)
    s_rings.push_back(-g.head_length);
  const double ds = g.pitch / rings_per_pitch;
  const unsigned int n_shaft = std::max(1u, static_cast<unsigned int>(std::ceil(g.length / ds)));
  for (unsigned int k = 0; k <= n_shaft; ++k)
    s_rings.push_back(g.length * k / n_shaft);
  const double tip_start = g.length - g.tip_length;
  if (g.tip_length > 0 && tip_start > 0)
    s_rings.push_back(tip_start);
  std::sort(s_rings.begin(), s_rings.end());
  s_rings.erase(std::unique(s_rings.begin(), s_rings.end(),
                            [&](double a, double b) { return std::abs(a - b) < 1e-6 * ds; }),
                s_rings.end());

  Tessellation t;
  const double rc = 0.5 * g.cannulation_diameter;
  // Ring k, ray j of the outer surface. The head's radius holds on [−head_length, 0): its
  // ring at s = 0⁻ sits at s = 0 with the head's radius, next to the shaft's first ring.
  std::vector<std::vector<unsigned int>> outer;
  auto add_ring = [&](double s, auto radius_at) {
    std::vector<unsigned int> ring(rays);
    for (unsigned int j = 0; j < rays; ++j) {
      const double theta = -pi + 2 * pi * j / rays;
      ring[j] = t.points.size();
      t.points.push_back(screw.at(s, radius_at(s, theta), theta));
    }
    return ring;
  };
  auto outer_radius = [&](double s, double theta) { return screw.surface_radius(s, theta); };
  for (const double s : s_rings) {
    if (g.head_length > 0 && std::abs(s) < 1e-6 * ds)
      outer.push_back(add_ring(0.0, [&](double, double) { return 0.5 * g.head_diameter; }));
    outer.push_back(add_ring(s, outer_radius));
  }
  // Between rings a and b (b − a = w) the triangles (a_j, b_j+1, b_j) and (a_j, a_j+1, b_j+1)
  // have the normal e_θ × w, with (e_r, e_θ, direction) right-handed: e_r for w along the
  // direction (the outer surface), −direction for w = e_r (the top annulus); `flip` reverses.
  auto quads = [&](const std::vector<unsigned int>& a, const std::vector<unsigned int>& b,
                   bool flip) {
    for (unsigned int j = 0; j < rays; ++j) {
      const unsigned int jn = (j + 1) % rays;
      std::array<unsigned int, 3> t1{{a[j], b[jn], b[j]}}, t2{{a[j], a[jn], b[jn]}};
      if (flip) {
        std::swap(t1[1], t1[2]);
        std::swap(t2[1], t2[2]);
      }
      t.triangles.push_back(t1);
      t.triangles.push_back(t2);
    }
  };
  for (std::size_t k = 0; k + 1 < outer.size(); ++k)
    quads(outer[k], outer[k + 1], false);
  const double s_top = s_rings.front(), s_end = s_rings.back();
  if (rc > 0) {
    // The bore: an inner cylinder joined to both ends by annuli.
    const auto top = add_ring(s_top, [&](double, double) { return rc; });
    const auto end = add_ring(s_end, [&](double, double) { return rc; });
    quads(top, end, true);
    quads(top, outer.front(), false);
    quads(end, outer.back(), true);
  } else {
    // Flat ends: fans about the axis, (c, ring_j+1, ring_j) facing −direction.
    for (const auto& [ring, s, flip] :
         {std::tuple{outer.front(), s_top, false}, std::tuple{outer.back(), s_end, true}}) {
      const unsigned int centre = t.points.size();
      t.points.push_back(screw.axis_point(s));
      for (unsigned int j = 0; j < rays; ++j) {
        std::array<unsigned int, 3> tri{{centre, ring[(j + 1) % rays], ring[j]}};
        if (flip)
          std::swap(tri[1], tri[2]);
        t.triangles.push_back(tri);
      }
    }
  }
  return t;
}

Tessellation surface_of(const ScrewSolid& screw) {
  if (const auto* stl = dynamic_cast<const StlScrew*>(&screw))
    return {stl->surface().vertices(), stl->surface().triangles()};
  return tessellate(dynamic_cast<const PedicleScrew&>(screw));
}

TriangleSolid surface_solid(const ScrewSolid& screw) {
  const auto t = surface_of(screw);
  return TriangleSolid(t.points, t.triangles,
                       dynamic_cast<const StlScrew*>(&screw)
                           ? "Screw/STL file"
                           : "Screw (the parametric screw's tessellation)");
}

} // namespace spinesim::implants
