// Screws from STL (implants/stl_screw, implants/triangle_solid through CGAL): the parametric
// screw's tessellation encloses its closed-form volume, survives a round trip through a binary
// STL file, and lands on the parametric solid when placed anywhere; a surface that is open,
// self-intersecting, unreadable or in the wrong units is bad input naming the file.

#include "base/exceptions.h"
#include "implants/pedicle_screw.h"
#include "implants/screw_tessellation.h"
#include "implants/stl_screw.h"
#include "implants/triangle_solid.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

using namespace spinesim;
using namespace spinesim::implants;

namespace {

constexpr double pi = 3.14159265358979323846;

PedicleScrewGeometry short_screw(bool cannulated) {
  PedicleScrewGeometry g;
  g.major_diameter = 6.5e-3;
  g.minor_diameter = 4.5e-3;
  g.pitch = 2.8e-3;
  g.crest_width = 0.3e-3;
  g.lead_flank_angle = 5;
  g.trail_flank_angle = 35;
  g.length = 8.4e-3; // three pitches
  g.tip_length = 2e-3;
  g.tip_ratio = 0.6;
  g.cannulation_diameter = cannulated ? 1e-3 : 0;
  g.head_diameter = 8e-3;
  g.head_length = 2e-3;
  g.direction = dealii::Tensor<1, 3>({0, 0, -1});
  return g;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("spinesim_stl_" + std::to_string(::getpid()) + "_" + name);
}

// The tessellation in file units (mm), as a binary STL.
std::filesystem::path write_screw(const PedicleScrew& screw, const std::string& name) {
  Tessellation t = tessellate(screw);
  for (auto& p : t.points)
    p *= 1e3;
  const auto file = temp_file(name);
  TriangleSolid::write_stl(file.string(), t.points, t.triangles);
  return file;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.where() + " | " + e.problem() + " | " + e.allowed();
  }
  return "no InvalidInput";
}

} // namespace

TEST(StlScrew, TessellationEnclosesTheClosedFormVolume) {
  for (const bool cannulated : {false, true}) {
    const PedicleScrew screw(short_screw(cannulated));
    const Tessellation t = tessellate(screw);
    const TriangleSolid solid(t.points, t.triangles, "test");
    // Chords of 128 rays cut π r² by (2π/128)²/6 = 4.0e-4 of the area; the rings (48 per
    // pitch) cut the thread's kinks, where the profile turns, by less. The closed form itself
    // is exact (Pappus on the tooth profile). Measured 5.6e-4 short; 1e-3 holds both.
    EXPECT_NEAR(solid.volume() / screw.volume(), 1.0, 1e-3) << "cannulated " << cannulated;
    EXPECT_LT(solid.volume(), screw.volume()) << "inscribed chords lose volume";
  }
}

TEST(StlScrew, RoundTripLandsOnTheParametricSolid) {
  // Written in the screw's own frame (entry at the origin, axis −z, mm) and placed obliquely:
  // the frame about the axis maps onto the scene's, so the threads coincide.
  const PedicleScrew own(short_screw(true));
  const auto file = write_screw(own, "roundtrip.stl");
  PedicleScrewGeometry placed = short_screw(true);
  placed.entry = dealii::Point<3>(1e-3, -2e-3, 0.5e-3);
  placed.direction = dealii::Tensor<1, 3>({0.3, -0.2, -1.0});
  const PedicleScrew reference(placed);
  StlPlacement where_in_file;
  where_in_file.file = file.string();
  where_in_file.unit = 1e-3;
  where_in_file.direction = dealii::Tensor<1, 3>({0, 0, -1});
  const StlScrew stl(placed, where_in_file, "Screw/STL file");
  std::filesystem::remove(file);

  // Binary STL stores floats: 7 digits on 10 mm move points by 1e-6 mm at most.
  EXPECT_NEAR(stl.volume() / reference.volume(), 1.0, 1e-3);
  EXPECT_NEAR(stl.bounding_radius(), reference.bounding_radius(), 1e-9);
  EXPECT_NEAR(stl.bounding_s_min(), -placed.head_length, 1e-9);
  EXPECT_NEAR(stl.bounding_s_max(), placed.length, 1e-9);

  // Points in the bounding cylinder: the two solids disagree only between the chords and the
  // surface. Along a ray the chord departs from R(s, θ) by at most a quarter ring spacing times
  // the steepest slope |dR/ds| = 1/tan(lead flank 5°) = 11.4 at a kink of the profile:
  // 11.4 × (2.8 mm / 48) / 4 = 0.17 mm, so no disagreement lies farther than 0.25 mm from the
  // surface along the ray or from an end plane. The disagreeing fraction of the cylinder is
  // the volume between chords and surface over the cylinder's, about 5.6e-4 × screw /
  // cylinder volume: measured 0.065 %, bound 0.5 %.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  unsigned int n = 0, disagree = 0, far_disagree = 0;
  const double R = reference.bounding_radius();
  for (unsigned int i = 0; i < 40000; ++i) {
    const double s = -placed.head_length + u(rng) * (placed.length + placed.head_length);
    const double r = R * std::sqrt(u(rng)), theta = 2 * pi * u(rng);
    const dealii::Point<3> x = reference.at(s, r, theta);
    ++n;
    if (reference.inside(x) != stl.inside(x)) {
      ++disagree;
      // Distance to the parametric surface along the ray, or to an end plane.
      const double dr = std::abs(r - reference.surface_radius(s, theta));
      const double ds =
          std::min({std::abs(s + placed.head_length), std::abs(s), std::abs(s - placed.length)});
      const double dc = std::abs(r - 0.5 * placed.cannulation_diameter);
      if (std::min({dr, ds, dc}) > 0.25e-3)
        ++far_disagree;
    }
  }
  EXPECT_LT(double(disagree) / n, 0.005);
  EXPECT_EQ(far_disagree, 0u);
  EXPECT_GT(disagree, 0u) << "a tessellation differs from its solid somewhere";
}

TEST(StlScrew, ClockwiseFileIsTurnedOutward) {
  const PedicleScrew screw(short_screw(false));
  Tessellation t = tessellate(screw);
  for (auto& tri : t.triangles)
    std::swap(tri[1], tri[2]);
  const TriangleSolid solid(t.points, t.triangles, "test");
  EXPECT_NEAR(solid.volume() / screw.volume(), 1.0, 1e-3);
  EXPECT_TRUE(solid.inside(screw.axis_point(4e-3)));
  EXPECT_FALSE(solid.inside(screw.at(4e-3, 5e-3, 0)));
}

// Signed distances (TriangleSolid::signed_distance, the contact's surface): a unit cube's are
// exact (bound 1e-12 m: round-off of the AABB tree's closest point). The screw's tessellation:
// on the shaft the distance lies between those to the major and to the core cylinders (the
// shaft lies between them), and on the axis it is the core's radius, within the tessellation's
// chord error (128 rays: r (1 − cos(π/128)) = 1 µm at the crest; bound 2 µm); the sign agrees
// with the point test away from the surface, and x − d n lies on it (bound 1e-9 m).
TEST(StlScrew, SignedDistanceOfCubeAndScrew) {
  std::vector<dealii::Point<3>> p;
  for (unsigned int k = 0; k < 8; ++k)
    p.emplace_back(k & 1, (k >> 1) & 1, (k >> 2) & 1);
  const std::vector<std::array<unsigned int, 3>> t = {
      {{0, 2, 1}}, {{1, 2, 3}}, {{4, 5, 6}}, {{5, 7, 6}}, {{0, 1, 4}}, {{1, 5, 4}},
      {{2, 6, 3}}, {{3, 6, 7}}, {{0, 4, 2}}, {{2, 4, 6}}, {{1, 3, 5}}, {{3, 7, 5}}};
  const TriangleSolid cube(p, t, "test cube");
  dealii::Tensor<1, 3> n;
  EXPECT_NEAR(cube.signed_distance(dealii::Point<3>(0.5, 0.5, 0.5), n), -0.5, 1e-12);
  EXPECT_NEAR(cube.signed_distance(dealii::Point<3>(0.5, 0.3, 0.6), n), -0.3, 1e-12);
  EXPECT_NEAR(n[1], -1.0, 1e-12);
  EXPECT_NEAR(cube.signed_distance(dealii::Point<3>(2.0, 0.5, 0.5), n), 1.0, 1e-12);
  EXPECT_NEAR(n[0], 1.0, 1e-12);
  EXPECT_NEAR(cube.signed_distance(dealii::Point<3>(2.0, 2.0, 0.5), n), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(n[0], std::sqrt(0.5), 1e-12);

  const PedicleScrew screw(short_screw(false));
  const TriangleSolid surface = surface_solid(screw);
  const auto& g = screw.geometry();
  std::mt19937 rng(7);
  // Clear of the head (s < 0, wider than the thread) by more than r − R_major, and of the tip.
  std::uniform_real_distribution<double> s_of(2e-3, 5.5e-3), r_of(0, 5e-3), a_of(-pi, pi);
  for (unsigned int k = 0; k < 400; ++k) {
    const double s = s_of(rng), r = r_of(rng), theta = a_of(rng);
    const auto x = screw.at(s, r, theta);
    const double d = surface.signed_distance(x, n);
    ASSERT_TRUE(std::isfinite(d));
    // The tessellation's rings lie 58 µm apart (pitch / 48), and its near-radial lead flank sits
    // up to that far from the closed-form one: the sign is checked farther from the surface.
    if (std::abs(d) > 6e-5) {
      EXPECT_EQ(d < 0, screw.inside(x)) << "s " << s << ", r " << r << ", d " << d;
    }
    EXPECT_NEAR(n.norm(), 1.0, 1e-9);
    // The shaft lies between its core and major cylinders, so the distance does too.
    if (r > 0.5 * g.major_diameter) {
      EXPECT_GT(d, r - 0.5 * g.major_diameter - 2e-6);
    }
    if (r > 0.5 * g.minor_diameter) {
      EXPECT_LT(d, r - 0.5 * g.minor_diameter + 2e-6);
    }
    // x − d n is the nearest surface point: on the surface (n points out of the solid).
    dealii::Tensor<1, 3> m;
    EXPECT_NEAR(surface.signed_distance(x - d * n, m), 0.0, 1e-9);
  }
  // On the axis the nearest surface is the core's or a root's: the distance is the minor
  // radius when the tooth is far (between roots, at most that).
  const double on_axis = surface.signed_distance(screw.axis_point(3e-3), n);
  EXPECT_LT(on_axis, -0.5 * g.minor_diameter + 2e-6);
  EXPECT_GT(on_axis, -0.5 * g.minor_diameter - 2e-6);
}

TEST(StlScrew, BadSurfacesAreBadInput) {
  const PedicleScrew screw(short_screw(false));
  const Tessellation good = tessellate(screw);

  // An open surface: two triangles removed.
  Tessellation open = good;
  open.triangles.erase(open.triangles.begin() + 100, open.triangles.begin() + 102);
  EXPECT_NE(message_of([&] {
              TriangleSolid(open.points, open.triangles, "Screw/STL file");
            }).find("not closed"),
            std::string::npos);

  // Two overlapping copies: self-intersecting.
  Tessellation twice = good;
  const unsigned int n = good.points.size();
  for (const auto& p : good.points)
    twice.points.push_back(p + dealii::Tensor<1, 3>({1e-3, 0, 0}));
  for (const auto& tri : good.triangles)
    twice.triangles.push_back({{tri[0] + n, tri[1] + n, tri[2] + n}});
  EXPECT_NE(message_of([&] {
              TriangleSolid(twice.points, twice.triangles, "Screw/STL file");
            }).find("intersects itself"),
            std::string::npos);

  // Not STL; missing.
  const auto garbage = temp_file("garbage.stl");
  std::ofstream(garbage) << "this is not a surface\n";
  const std::string m1 = message_of([&] { TriangleSolid(garbage.string(), "Screw/STL file", 1); });
  EXPECT_NE(m1.find("Screw/STL file"), std::string::npos) << m1;
  EXPECT_NE(m1.find("not a readable STL"), std::string::npos) << m1;
  EXPECT_NE(m1.find(garbage.string()), std::string::npos) << m1;
  std::filesystem::remove(garbage);
  EXPECT_NE(message_of([&] {
              TriangleSolid("/nonexistent/screw.stl", "Screw/STL file", 1);
            }).find("no such file"),
            std::string::npos);

  // A truncated binary file.
  const auto file = write_screw(screw, "truncated.stl");
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  EXPECT_NE(message_of([&] {
              TriangleSolid(file.string(), "Screw/STL file", 1e-3);
            }).find("not a readable STL"),
            std::string::npos);
  std::filesystem::remove(file);
}

TEST(StlScrew, WrongUnitsOrPlacementIsBadInput) {
  const PedicleScrew screw(short_screw(false));
  const auto file = write_screw(screw, "units.stl");
  StlPlacement p;
  p.file = file.string();
  p.direction = dealii::Tensor<1, 3>({0, 0, -1});
  // Read as metres: 1000 times too large.
  p.unit = 1;
  const std::string m1 = message_of([&] { StlScrew(short_screw(false), p, "Screw/STL file"); });
  EXPECT_NE(m1.find("reaches 8400 mm along the axis"), std::string::npos) << m1;
  EXPECT_NE(m1.find("STL units"), std::string::npos) << m1;
  // The axis reversed: the shaft points out of the bone.
  p.unit = 1e-3;
  p.direction = dealii::Tensor<1, 3>({0, 0, 1});
  const std::string m2 = message_of([&] { StlScrew(short_screw(false), p, "Screw/STL file"); });
  EXPECT_NE(m2.find("reaches 2 mm along the axis"), std::string::npos) << m2;
  EXPECT_NE(m2.find("STL axis"), std::string::npos) << m2;
  // Nominal Major diameter not the file's.
  p.direction = dealii::Tensor<1, 3>({0, 0, -1});
  PedicleScrewGeometry wider = short_screw(false);
  wider.major_diameter = 7.5e-3;
  const std::string m3 = message_of([&] { StlScrew(wider, p, "Screw/STL file"); });
  EXPECT_NE(m3.find("outer diameter on the surface is 6.5 mm, the Major diameter is 7.5 mm"),
            std::string::npos)
      << m3;
  // And the right placement reads.
  EXPECT_NO_THROW(StlScrew(short_screw(false), p, "Screw/STL file"));
  std::filesystem::remove(file);
}
