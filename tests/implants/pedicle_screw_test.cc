// The parametric pedicle screw: its point-in-solid test integrates to the closed-form volume
// (Pappus for the helical thread), the tooth sits where its profile says, the solid turns
// with its direction, and an impossible screw is bad input naming the entry.

#include "base/exceptions.h"
#include "implants/pedicle_screw.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace spinesim;
using namespace spinesim::implants;

namespace {

constexpr double pi = 3.14159265358979323846;

PedicleScrewGeometry short_screw() {
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
  g.cannulation_diameter = 1e-3;
  g.head_diameter = 8e-3;
  g.head_length = 2e-3;
  g.entry = dealii::Point<3>(1e-3, -2e-3, 0.5e-3);
  g.direction = dealii::Tensor<1, 3>({0.3, -0.2, -1.0});
  return g;
}

// ∫ 1_inside dV in the screw's cylindrical coordinates, midpoint rule.
double integrate_volume(const PedicleScrew& screw, unsigned int ns, unsigned int nr,
                        unsigned int nt) {
  const auto& g = screw.geometry();
  const double s0 = -g.head_length, s1 = g.length, R = screw.bounding_radius() * 1.01;
  dealii::Tensor<1, 3> e1;
  e1[0] = 1;
  e1 -= (e1 * g.direction) * g.direction;
  e1 /= e1.norm();
  const dealii::Tensor<1, 3> e2 = dealii::cross_product_3d(g.direction, e1);
  const double ds = (s1 - s0) / ns, dr = R / nr, dt = 2 * pi / nt;
  double v = 0;
  for (unsigned int i = 0; i < ns; ++i) {
    const double s = s0 + (i + 0.5) * ds;
    for (unsigned int j = 0; j < nr; ++j) {
      const double r = (j + 0.5) * dr;
      unsigned int hits = 0;
      for (unsigned int k = 0; k < nt; ++k) {
        const double t = (k + 0.5) * dt;
        hits += screw.inside(screw.axis_point(s) + r * std::cos(t) * e1 + r * std::sin(t) * e2);
      }
      v += hits * dt * r * dr * ds;
    }
  }
  return v;
}

} // namespace

TEST(PedicleScrew, PointTestIntegratesToTheClosedFormVolume) {
  const PedicleScrew screw(short_screw());
  const double exact = screw.volume();
  // Midpoint rule on an indicator: the error is O(h) over the surface, here ~ (surface area
  // ~ 3e-4 m^2) × (h/2 ~ 5e-6 m) / 4 (errors of both signs partly cancel) ≈ 0.3 % of the
  // ~1.9e-7 m^3 volume at 1000 × 160 × 360 points; 0.5 % bounds it, and a wrong tooth width,
  // depth or tip law changes the volume by more than 2 %.
  const double v = integrate_volume(screw, 1000, 160, 360);
  EXPECT_NEAR(v, exact, 5e-3 * exact) << "closed form " << exact << " m^3";
  // The thread is a real part of it: the volume of the bare core differs by more than 10 %.
  const auto& g = screw.geometry();
  const double core = pi * 0.25 * g.minor_diameter * g.minor_diameter * g.length;
  EXPECT_GT(std::abs(exact - core), 0.1 * exact);
}

TEST(PedicleScrew, ToothProfileAndHelix) {
  PedicleScrewGeometry g = short_screw();
  g.tip_length = 0;
  g.cannulation_diameter = 0;
  g.entry = dealii::Point<3>();
  g.direction = dealii::Tensor<1, 3>({0, 0, -1});
  const PedicleScrew screw(g);
  const double p = g.pitch, d = g.thread_depth(), rm = 0.5 * g.minor_diameter;
  const double w = g.root_width();
  // Find the angle-zero half plane: points at radius rm + y along +e1 of the screw's frame are
  // found by scanning s; the tooth must occupy an axial band of width(y) = w − y (tan α_l +
  // tan α_t) once per pitch, at every radius within the depth.
  dealii::Tensor<1, 3> any;
  any[0] = 1;
  for (const double y : {0.1 * d, 0.5 * d, 0.9 * d}) {
    SCOPED_TRACE(y);
    const unsigned int n = 28000; // 1e-7 m steps over one pitch + margin
    unsigned int inside = 0;
    for (unsigned int i = 0; i < n; ++i) {
      const double s = 2.0 * p + p * (i + 0.5) / n; // one full pitch in the shaft
      inside += screw.inside(screw.axis_point(s) + (rm + y) * any);
    }
    const double width = w - y * (std::tan(5 * pi / 180) + std::tan(35 * pi / 180));
    // Sampling at p/n = 1e-7 m: the band's measured width is within two samples.
    EXPECT_NEAR(inside * p / n, width, 2.0 * p / n);
  }
  // The core is solid, the crest radius is the limit, beyond it nothing.
  EXPECT_TRUE(screw.inside(screw.axis_point(3e-3) + 0.99 * rm * any));
  EXPECT_FALSE(screw.inside(screw.axis_point(3e-3) + (rm + 1.01 * d) * any));
  // The helix: rotating the probe by angle θ shifts the tooth by p θ/2π along the axis.
  const dealii::Point<3> probe = screw.axis_point(3e-3) + (rm + 0.5 * d) * any;
  unsigned int agree = 0;
  for (unsigned int k = 0; k < 64; ++k) {
    const double theta = 2 * pi * k / 64, c = std::cos(theta), sn = std::sin(theta);
    // Rotation about z (the axis) by θ; the screw turns the thread by +θ → shift along s.
    const dealii::Point<3> rotated(c * probe[0] - sn * probe[1], sn * probe[0] + c * probe[1],
                                   probe[2]);
    const bool a = screw.inside(rotated + p * theta / (2 * pi) * g.direction);
    const bool b = screw.inside(rotated - p * theta / (2 * pi) * g.direction);
    agree += (a == screw.inside(probe)) || (b == screw.inside(probe));
  }
  EXPECT_EQ(agree, 64u);
}

TEST(PedicleScrew, TurnsWithItsDirection) {
  PedicleScrewGeometry a = short_screw(), b = short_screw();
  b.direction = -a.direction;
  const PedicleScrew sa(a), sb(b);
  // Mirror through the entry point: the same solid up to the thread's phase, so the volumes
  // agree and the head is on the other side.
  EXPECT_NEAR(sa.volume(), sb.volume(), 1e-15);
  // A point in the head of `a` (radius 3.5 mm < head 4 mm, beyond the 3.25 mm major radius)
  // lies beside the shaft of `b`, outside it.
  dealii::Tensor<1, 3> across =
      dealii::cross_product_3d(sa.geometry().direction, dealii::Tensor<1, 3>({1, 0, 0}));
  across /= across.norm();
  const dealii::Point<3> x = sa.axis_point(-1e-3) + 3.5e-3 * across;
  EXPECT_TRUE(sa.inside(x));
  EXPECT_FALSE(sb.inside(x));
  EXPECT_DOUBLE_EQ(sa.distance_to_bounding_cylinder(sa.axis_point(3e-3)), 0.0);
  EXPECT_NEAR(sa.distance_to_bounding_cylinder(sa.axis_point(a.length + 1e-3)), 1e-3, 1e-15);
}

TEST(PedicleScrew, ImpossibleScrewsAreBadInputNamingTheEntry) {
  auto expect_invalid = [](PedicleScrewGeometry g, const std::string& entry) {
    try {
      PedicleScrew s(g);
      FAIL() << entry << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(entry), std::string::npos) << e.what();
    }
  };
  PedicleScrewGeometry g = short_screw();
  g.pitch = 0.9e-3; // below the 1 mm thread depth
  expect_invalid(g, "Screw/Pitch");
  g = short_screw();
  g.pitch = 1.05e-3; // above the depth but narrower than the tooth's 1.09 mm root
  expect_invalid(g, "Screw/Pitch");
  g = short_screw();
  g.major_diameter = 4e-3;
  expect_invalid(g, "Screw/Major diameter");
  g = short_screw();
  g.tip_length = 9e-3;
  expect_invalid(g, "Screw/Tip length");
  g = short_screw();
  g.cannulation_diameter = 3e-3;
  expect_invalid(g, "Screw/Cannulation diameter");
  g = short_screw();
  g.direction = dealii::Tensor<1, 3>();
  expect_invalid(g, "Screw/Direction");
}
