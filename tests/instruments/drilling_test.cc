// The twist and step drills: the mechanistic force model integrates to its closed forms
// (Kienzle's specific cutting force over straight lips), the thrust control inverts it, the
// programme runs its phases for the times they should take and integrates the cutting power
// exactly where the closed form is known, and the swept solid's distance is right on each
// part of the bit's profile.

#include "base/exceptions.h"
#include "instruments/drilling_programme.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace spinesim;
using namespace spinesim::instruments;

namespace {

CuttingCoefficients cortical() {
  CuttingCoefficients c;
  c.tangential = 200e6;
  c.thrust = 300e6;
  c.exponent = 0.3;
  c.reference_chip_thickness = 0.05e-3;
  return c;
}

DrillBit bit(double pilot = 0) {
  DrillBit b;
  b.diameter = 4e-3;
  b.point_angle = 118;
  b.pilot_diameter = pilot;
  return b;
}

// A hole fed along -z from (x, 0, 0), the block's top face at z = 0.
DrillHole downward_hole(double depth, double x = 0) {
  DrillHole h;
  h.axis.entry = dealii::Point<3>(x, 0, 0);
  h.axis.direction = dealii::Tensor<1, 3>({0, 0, -1});
  h.depth = depth;
  return h;
}

// The programme's material: cortical bone below the top face (a >= 0), air above it.
std::optional<CuttingCoefficients> cortical_below_top(unsigned int, double a, double, double) {
  if (a < 0)
    return std::nullopt;
  return cortical();
}

} // namespace

// Fully engaged in one material: M = K_c(h) f (R² − r_p²)/2 and F = K_t(h) f sin κ (R − r_p)
// with h = (f/2) sin κ; the midpoint rule is exact for these integrands (linear and constant
// in r), so the tolerance is round-off.
TEST(DrillingForces, FullyEngagedLipsMatchClosedForm) {
  const CuttingCoefficients c = cortical();
  for (const double pilot : {0.0, 1.5e-3}) {
    const DrillingForceModel model(bit(pilot));
    const auto everywhere = [&](double, double, double) {
      return std::optional<CuttingCoefficients>(c);
    };
    const double f = 0.06e-3, rpm = 1000, tip = 20e-3;
    const DrillingLoad L = model.load(tip, f, rpm, everywhere);
    const double kappa = 59.0 * pi / 180, h = 0.5 * f * std::sin(kappa);
    const double R = 2e-3, rp = 0.5 * pilot;
    const double M = c.tangential_at(h) * f * (R * R - rp * rp) / 2;
    const double F = c.thrust_at(h) * f * std::sin(kappa) * (R - rp);
    EXPECT_NEAR(L.torque, M, 1e-12 * M);
    EXPECT_NEAR(L.thrust, F, 1e-12 * F);
    EXPECT_NEAR(L.power, M * 2 * pi * rpm / 60 + F * f * rpm / 60, 1e-12 * L.power);
    EXPECT_DOUBLE_EQ(L.engaged_fraction, 1.0);
  }
}

// Entering a flat surface, only the lip within r_e = s tan κ of the axis cuts: M = K f r_e²/2
// up to the one lip sample the surface crosses (|error| <= K f R dr).
TEST(DrillingForces, PartialEngagementAtEntry) {
  const CuttingCoefficients c = cortical();
  const DrillingForceModel model(bit(), 256);
  const auto bone_below_surface = [&](double a, double,
                                      double) -> std::optional<CuttingCoefficients> {
    if (a < 0)
      return std::nullopt;
    return c;
  };
  const double f = 0.06e-3, kappa = 59.0 * pi / 180, h = 0.5 * f * std::sin(kappa);
  const double s = 0.5e-3, re = s * std::tan(kappa), R = 2e-3, dr = R / 256;
  const DrillingLoad L = model.load(s, f, 1000, bone_below_surface);
  EXPECT_NEAR(L.torque, c.tangential_at(h) * f * re * re / 2, c.tangential_at(h) * f * R * dr);
  EXPECT_NEAR(L.engaged_fraction, re / R, 1.0 / 256);
  EXPECT_EQ(model.load(-1e-3, f, 1000, bone_below_surface).torque, 0.0); // in air
}

TEST(DrillingForces, ThrustControlInvertsTheModel) {
  const CuttingCoefficients c = cortical();
  const DrillingForceModel model(bit());
  const auto everywhere = [&](double, double, double) {
    return std::optional<CuttingCoefficients>(c);
  };
  const double f = model.feed_for_thrust(5e-3, 40.0, 1200, everywhere, 1e-3);
  EXPECT_NEAR(model.load(5e-3, f, 1200, everywhere).thrust, 40.0, 1e-8);
  // Nothing to cut: no feed from thrust.
  EXPECT_EQ(model.feed_for_thrust(
                5e-3, 40.0, 1200,
                [](double, double, double) { return std::optional<CuttingCoefficients>(); }, 1e-3),
            0.0);
}

// Per revolution a lip element cuts what lies on its circle: bone on half the circle (an
// edge, an earlier hole) halves the forces, and K_ref (1 + cos θ) averages to K_ref. Both
// exact for the midpoint rule in θ (a step function split at sample boundaries, a cosine of
// degree below the sample count): round-off.
TEST(DrillingForces, LipsAverageTheirCircle) {
  const CuttingCoefficients c = cortical();
  const DrillingForceModel model(bit());
  const double f = 0.06e-3, rpm = 1000, tip = 20e-3;
  const auto everywhere = [&](double, double, double) {
    return std::optional<CuttingCoefficients>(c);
  };
  const DrillingLoad full = model.load(tip, f, rpm, everywhere);
  const auto half = [&](double, double, double theta) -> std::optional<CuttingCoefficients> {
    if (theta > pi)
      return std::nullopt;
    return c;
  };
  const DrillingLoad L = model.load(tip, f, rpm, half);
  EXPECT_NEAR(L.torque, 0.5 * full.torque, 1e-12 * full.torque);
  EXPECT_NEAR(L.thrust, 0.5 * full.thrust, 1e-12 * full.thrust);
  EXPECT_DOUBLE_EQ(L.engaged_fraction, 0.5);
  const auto varying = [&](double, double, double theta) {
    CuttingCoefficients v = c;
    v.tangential *= 1 + std::cos(theta);
    v.thrust *= 1 + std::cos(theta);
    return std::optional<CuttingCoefficients>(v);
  };
  const DrillingLoad V = model.load(tip, f, rpm, varying);
  EXPECT_NEAR(V.torque, full.torque, 1e-12 * full.torque);
  EXPECT_NEAR(V.thrust, full.thrust, 1e-12 * full.thrust);
}

// Two holes at constant feed: the phases take depth/v, the dwell, depth/v_r and the pause;
// the cutting energy over the feed equals the closed form ∫ P dt of a cone entering a
// half-space then cutting fully engaged:
//   ∫ M ω dt = K f ω R² [ (d − L_c) / (2v) + L_c / (6v) ]   (L_c = R / tan κ),
// up to the lip and time sampling (64 lips, 400 steps: 2e-3 relative).
TEST(DrillingProgramme, PhasesAndCuttingEnergy) {
  const CuttingCoefficients c = cortical();
  DrillingSchedule sched;
  sched.spindle_rpm = 1000;
  sched.feed_rate = 1e-3;
  sched.dwell = 0.5;
  sched.retraction_speed = 5e-3;
  sched.pause = 1.0;
  sched.margin_friction_torque = 2e-3;
  const DrillHole hole = downward_hole(5e-3);
  const DrillHole second = downward_hole(5e-3, 8e-3);
  const DrillingProgramme programme(DrillingForceModel(bit()), {hole, second}, sched);
  const auto material = cortical_below_top;
  DrillState st = programme.initial_state();
  const double feed_time = 5.0, total = programme.nominal_duration();
  EXPECT_NEAR(total, 2 * (5.0 + 0.5 + 1.0 + 1.0), 1e-12);
  double cutting = 0, torque_part = 0, friction = 0, in_bone = 0, t = 0;
  const double dt = feed_time / 400;
  while (t < feed_time - 1e-12) {
    const DrillInterval I = programme.advance(st, dt, 1, material);
    cutting += I.cutting_energy;
    torque_part += I.torque_energy;
    friction += I.friction_energy;
    in_bone += I.time_in_bone;
    t += dt;
  }
  EXPECT_EQ(st.phase, DrillPhase::dwell);
  EXPECT_NEAR(st.tip, 5e-3, 1e-15);
  const double f = 1e-3 * 60 / 1000, kappa = 59.0 * pi / 180, h = 0.5 * f * std::sin(kappa);
  const double R = 2e-3, Lc = R / std::tan(kappa), v = 1e-3, omega = 2 * pi * 1000 / 60.0;
  const double torque_energy =
      c.tangential_at(h) * f * omega * R * R * ((5e-3 - Lc) / (2 * v) + Lc / (6 * v));
  const double thrust_energy =
      c.thrust_at(h) * f * std::sin(kappa) * R * v * ((5e-3 - Lc) / v + Lc / (2 * v));
  EXPECT_NEAR(cutting, torque_energy + thrust_energy, 2e-3 * cutting);
  EXPECT_NEAR(torque_part, torque_energy, 2e-3 * torque_energy);
  // The rest of the programme in one call, split exactly at the phase ends.
  const DrillInterval rest = programme.advance(st, total - feed_time + 1.0, 50, material);
  EXPECT_EQ(st.phase, DrillPhase::done);
  EXPECT_NEAR(st.deepest[0], 5e-3, 1e-15);
  EXPECT_NEAR(st.deepest[1], 5e-3, 1e-15);
  // Margin friction while the bit is in a hole: both feeds, dwells and retractions.
  friction += rest.friction_energy;
  in_bone += rest.time_in_bone;
  EXPECT_NEAR(in_bone, 2 * (5.0 + 0.5 + 1.0), 1e-9);
  EXPECT_NEAR(friction, 2e-3 * omega * in_bone, 1e-12);
}

// Peck drilling: 5 mm in pecks of 2 mm. The bit withdraws to the entry after the pecks ending
// at 2 and 4 mm and returns down its hole at the retraction speed, so the programme takes
// 5 / v + 5 / v_r + 2 (2 + 4) / v_r. The cutting is that of the continuous feed: the phases
// between pecks cut nothing and the feed resumes on the bottom it left (the lips fully engaged
// from 1.2 mm on, where both runs still take the same steps), so the energies agree to
// round-off. Between pecks nothing deepens the hole, and each peck starts where the last one
// stopped (0, 2 and 4 mm).
TEST(DrillingProgramme, PeckDrillingWithdrawsBetweenPecks) {
  DrillingSchedule sched;
  sched.spindle_rpm = 1000;
  sched.feed_rate = 1e-3;
  sched.retraction_speed = 5e-3;
  const DrillHole hole = downward_hole(5e-3);
  const auto material = cortical_below_top;
  const DrillingProgramme continuous(DrillingForceModel(bit()), {hole}, sched);
  sched.peck_depth = 2e-3;
  const DrillingProgramme pecking(DrillingForceModel(bit()), {hole}, sched);
  EXPECT_NEAR(pecking.nominal_duration(), 5.0 + 1.0 + 2 * (2.0 + 4.0) / 5.0, 1e-12);

  auto run = [&](const DrillingProgramme& programme, std::vector<DrillPhase>& phases) {
    DrillState st = programme.initial_state();
    double cutting = 0, in_bone = 0;
    std::vector<double> peck_starts{st.peck_start};
    const double dt = 0.0117; // no phase ends on a step's end: dwell 0 and pause 0 never show
    for (unsigned int step = 0; step < 2000 && st.phase != DrillPhase::done; ++step) {
      const DrillPhase before = st.phase;
      const double deepest_before = st.deepest[0];
      const DrillInterval I = programme.advance(st, dt, 1, material);
      cutting += I.cutting_energy;
      in_bone += I.time_in_bone;
      if (phases.empty() || phases.back() != st.phase)
        phases.push_back(st.phase);
      if (st.phase != DrillPhase::done && st.peck_start != peck_starts.back())
        peck_starts.push_back(st.peck_start);
      if ((before == DrillPhase::peck_retract || before == DrillPhase::peck_return) &&
          st.phase != DrillPhase::feed) {
        EXPECT_EQ(st.deepest[0], deepest_before) << "step " << step;
      }
    }
    if (st.pecks > 0) {
      EXPECT_EQ(peck_starts.size(), 3u);
      if (peck_starts.size() == 3) {
        EXPECT_NEAR(peck_starts[1], 2e-3, 1e-15);
        EXPECT_NEAR(peck_starts[2], 4e-3, 1e-15);
      }
    }
    EXPECT_EQ(st.phase, DrillPhase::done);
    EXPECT_NEAR(st.deepest[0], 5e-3, 1e-15);
    return std::make_tuple(cutting, in_bone, st.pecks);
  };
  std::vector<DrillPhase> phases_continuous, phases_pecking;
  const auto [cut_c, bone_c, pecks_c] = run(continuous, phases_continuous);
  const auto [cut_p, bone_p, pecks_p] = run(pecking, phases_pecking);
  EXPECT_EQ(pecks_c, 0u);
  EXPECT_EQ(pecks_p, 2u);
  EXPECT_NEAR(cut_p, cut_c, 1e-9 * cut_c);
  EXPECT_NEAR(bone_c, 5.0 + 1.0, 1e-9);
  EXPECT_NEAR(bone_p, 5.0 + 1.0 + 2.4, 1e-9);
  const std::vector<DrillPhase> expected{
      DrillPhase::feed, DrillPhase::peck_retract, DrillPhase::peck_return,
      DrillPhase::feed, DrillPhase::peck_retract, DrillPhase::peck_return,
      DrillPhase::feed, DrillPhase::retract,      DrillPhase::done};
  std::vector<std::string> got, want;
  for (const auto p : phases_pecking)
    got.push_back(to_string(p));
  for (const auto p : expected)
    want.push_back(to_string(p));
  EXPECT_EQ(got, want);

  // Pecks under 1e-3 of the hole (more than a thousand) are refused.
  sched.peck_depth = 1e-6;
  try {
    DrillingProgramme(DrillingForceModel(bit()), {hole}, sched);
    ADD_FAILURE() << "a 1 um peck in a 5 mm hole was accepted";
  } catch (const spinesim::InvalidInput& e) {
    EXPECT_EQ(e.where(), "Drill/Peck depth");
  }
  sched.peck_depth = -1e-3;
  try {
    sched.validate();
    ADD_FAILURE() << "a negative peck depth was accepted";
  } catch (const spinesim::InvalidInput& e) {
    EXPECT_EQ(e.where(), "Drill/Peck depth");
  }
}

// Pecks under thrust control: each peck stops exactly at its depth (2 and 4 mm: the deepest
// point when the withdrawal starts), the thrust never passes the set 60 N (the bisection's
// 1e-6), and fully engaged in one bone the feed after a return is the feed before it (the same
// thrust balance).
TEST(DrillingProgramme, PecksUnderThrustControl) {
  DrillingSchedule sched;
  sched.spindle_rpm = 1000;
  sched.feed_rate = 1e-3;
  sched.thrust_control = true;
  sched.thrust_force = 60;
  sched.peck_depth = 2e-3;
  const DrillHole hole = downward_hole(5e-3);
  const DrillingProgramme programme(DrillingForceModel(bit()), {hole}, sched);
  const auto material = cortical_below_top;
  DrillState st = programme.initial_state();
  double max_thrust = 0;
  std::vector<double> deepest_at_withdrawal, feed_before, feed_after;
  double last_feed = 0;
  for (unsigned int step = 0; step < 4000 && st.phase != DrillPhase::done; ++step) {
    const DrillPhase before = st.phase;
    const DrillInterval I = programme.advance(st, 0.05, 8, material);
    max_thrust = std::max(max_thrust, I.max_thrust);
    if (before == DrillPhase::feed && st.phase == DrillPhase::peck_retract) {
      deepest_at_withdrawal.push_back(st.deepest[0]);
      feed_before.push_back(last_feed);
    }
    if (before == DrillPhase::peck_return && st.phase == DrillPhase::feed)
      feed_after.push_back(I.feed_per_rev);
    if (I.feed_per_rev > 0)
      last_feed = I.feed_per_rev;
    if (st.phase == DrillPhase::feed) {
      EXPECT_LE(st.tip, st.peck_start + 2e-3 + 1e-15) << "step " << step;
    }
  }
  EXPECT_EQ(st.phase, DrillPhase::done);
  EXPECT_EQ(st.pecks, 2u);
  EXPECT_LE(max_thrust, 60.0 * (1 + 1e-6));
  ASSERT_EQ(deepest_at_withdrawal.size(), 2u);
  EXPECT_NEAR(deepest_at_withdrawal[0], 2e-3, 1e-15);
  EXPECT_NEAR(deepest_at_withdrawal[1], 4e-3, 1e-15);
  ASSERT_EQ(feed_after.size(), 2u);
  for (unsigned int k = 0; k < 2; ++k) {
    EXPECT_GT(feed_before[k], 0.0);
    EXPECT_NEAR(feed_after[k], feed_before[k], 1e-6 * feed_before[k]) << "peck " << k;
  }
}

TEST(DrillBit, DistanceToSweptSolid) {
  const DrillBit b = bit();
  const double R = 2e-3, kappa = 59.0 * pi / 180, tip = 10e-3, Lc = R / std::tan(kappa);
  EXPECT_EQ(b.distance_outside(5e-3, 1e-3, tip), 0.0);
  EXPECT_NEAR(b.distance_outside(5e-3, 3.5e-3, tip), 1.5e-3, 1e-15); // wall
  // Straight below the tip on the axis: the tip itself is nearest.
  EXPECT_NEAR(b.distance_outside(tip + 1e-3, 0, tip), 1e-3, 1e-15);
  // Normal to the cone from a point beside the point: (distance along the normal) exactly.
  const dealii::Tensor<1, 2> normal({std::sin(kappa), std::cos(kappa)}); // (a, r), outward
  const double am = tip - 0.5 * Lc, rm = 0.5 * R;                        // cone midpoint
  EXPECT_NEAR(b.distance_outside(am + 0.3e-3 * normal[0], rm + 0.3e-3 * normal[1], tip), 0.3e-3,
              1e-15);
  // The same point mirrored inside: as far from the surface, and swept.
  EXPECT_NEAR(b.distance_to_surface(am - 0.3e-3 * normal[0], rm - 0.3e-3 * normal[1], tip), 0.3e-3,
              1e-15);
  EXPECT_EQ(b.distance_outside(am - 0.3e-3 * normal[0], rm - 0.3e-3 * normal[1], tip), 0.0);
  // Beyond the rim, outwards and below: the corner at (tip − L_c, R).
  EXPECT_NEAR(b.distance_outside(tip - Lc + 3e-3, R + 4e-3, tip), 5e-3, 1e-12);
  EXPECT_TRUE(b.swept(tip - 1e-9, 0, tip));
  EXPECT_FALSE(b.swept(tip - Lc + 1e-9, R - 1e-9, tip));
  EXPECT_DOUBLE_EQ(b.full_diameter_depth(), Lc);
}

namespace {
// A step drill: a 2.5 mm leading section 4 mm long (point 118°) and a 90° shoulder to 4 mm.
DrillBit step_drill(double pilot = 0) {
  DrillBit b = bit(pilot);
  b.step_diameter = 2.5e-3;
  b.step_length = 4e-3;
  b.shoulder_angle = 90;
  return b;
}
} // namespace

// The profile z(r) of a step drill is the leading point out to r_s, then the shoulder from
// (L_s, r_s) at 45° to (L_s + R − r_s, R); its four segments join, and the distances measure
// to the right one of them.
TEST(DrillBit, StepDrillProfile) {
  const DrillBit b = step_drill();
  const double kappa = 59.0 * pi / 180, rs = 1.25e-3, Ls = 4e-3, R = 2e-3, tip = 10e-3;
  EXPECT_NEAR(b.lip_depth(1e-3), 1e-3 / std::tan(kappa), 1e-15);
  EXPECT_NEAR(b.lip_depth(1.5e-3), Ls + 0.25e-3, 1e-15); // tan 45° = 1
  EXPECT_NEAR(b.full_diameter_depth(), Ls + R - rs, 1e-15);
  EXPECT_DOUBLE_EQ(b.half_angle_at(1e-3), kappa);
  EXPECT_DOUBLE_EQ(b.half_angle_at(1.5e-3), pi / 4);
  const auto p = b.profile(20e-3);
  ASSERT_EQ(p.size(), 4u);
  for (unsigned int i = 1; i < p.size(); ++i) {
    EXPECT_DOUBLE_EQ(p[i].z0, p[i - 1].z1);
    EXPECT_DOUBLE_EQ(p[i].r0, p[i - 1].r1);
  }
  EXPECT_TRUE(p[0].cutting && !p[1].cutting && p[2].cutting && !p[3].cutting);
  // Beside the leading section, in the ring the shoulder has not reached: not swept, and
  // nearest the leading margin.
  EXPECT_FALSE(b.swept(tip - 2e-3, 1.5e-3, tip));
  EXPECT_NEAR(b.distance_outside(tip - 2e-3, 1.5e-3, tip), 0.25e-3, 1e-15);
  EXPECT_NEAR(b.distance_to_margins(tip - 2e-3, 1.5e-3, tip), 0.25e-3, 1e-15);
  // Behind the shoulder: swept; its distance to the shoulder's lip along the 45° normal.
  const double a = tip - Ls - 0.5e-3, r = 1.5e-3; // the lip passes (tip − Ls − 0.25e-3, 1.5e-3)
  EXPECT_TRUE(b.swept(a, r, tip));
  EXPECT_NEAR(b.distance_to_lips(a, r, tip), 0.25e-3 / std::sqrt(2.0), 1e-15);
  // A pilot hole of 2 mm clips the leading point's lip to r >= 1 mm and leaves the shoulder.
  const auto lips = step_drill(2e-3).cutting_edges();
  ASSERT_EQ(lips.size(), 2u);
  EXPECT_DOUBLE_EQ(lips[0].r0, 1e-3);
  EXPECT_NEAR(lips[0].z0, 1e-3 / std::tan(kappa), 1e-15);
  EXPECT_DOUBLE_EQ(lips[1].r0, rs);
  // Pilot as wide as the leading section: only the shoulder cuts.
  EXPECT_EQ(step_drill(2.5e-3).cutting_edges().size(), 1u);
}

// Fully engaged, each lip gives its closed form at its own chip thickness h = (f/2) sin κ:
//   M = Σ K_c(h_i) f (r_hi² − r_lo²)/2,  F = Σ K_t(h_i) f sin κ_i (r_hi − r_lo),
// exact for the midpoint rule (round-off). While only the leading section is in bone (the
// shoulder above the surface), the forces are those of a twist drill of the leading diameter.
TEST(DrillingForces, StepDrillLipsMatchClosedForm) {
  const CuttingCoefficients c = cortical();
  const double f = 0.06e-3, rpm = 1000, R = 2e-3, rs = 1.25e-3;
  const double k1 = 59.0 * pi / 180, k2 = pi / 4;
  const double h1 = 0.5 * f * std::sin(k1), h2 = 0.5 * f * std::sin(k2);
  for (const double pilot : {0.0, 1e-3}) {
    const DrillingForceModel model(step_drill(pilot));
    const auto everywhere = [&](double, double, double) {
      return std::optional<CuttingCoefficients>(c);
    };
    const DrillingLoad L = model.load(20e-3, f, rpm, everywhere);
    const double rp = 0.5 * pilot;
    const double M = c.tangential_at(h1) * f * (rs * rs - rp * rp) / 2 +
                     c.tangential_at(h2) * f * (R * R - rs * rs) / 2;
    const double F = c.thrust_at(h1) * f * std::sin(k1) * (rs - rp) +
                     c.thrust_at(h2) * f * std::sin(k2) * (R - rs);
    EXPECT_NEAR(L.torque, M, 1e-12 * M) << "pilot " << pilot;
    EXPECT_NEAR(L.thrust, F, 1e-12 * F) << "pilot " << pilot;
    EXPECT_DOUBLE_EQ(L.engaged_fraction, 1.0);
  }
  // Tip 3.5 mm into a half space a >= 0: the leading point is in, the shoulder (4 mm behind the
  // tip) still above the surface.
  const auto below_surface = [&](double a, double, double) -> std::optional<CuttingCoefficients> {
    if (a < 0)
      return std::nullopt;
    return c;
  };
  DrillBit leading = bit();
  leading.diameter = 2.5e-3;
  const DrillingLoad S = DrillingForceModel(step_drill()).load(3.5e-3, f, rpm, below_surface);
  const DrillingLoad T = DrillingForceModel(leading).load(3.5e-3, f, rpm, below_surface);
  EXPECT_NEAR(S.torque, T.torque, 1e-12 * T.torque);
  EXPECT_NEAR(S.thrust, T.thrust, 1e-12 * T.thrust);
  EXPECT_NEAR(S.thrust, c.thrust_at(h1) * f * std::sin(k1) * rs, 1e-12 * S.thrust);
}

TEST(DrillBit, BadInputNamesTheEntry) {
  DrillBit b = bit(5e-3);
  try {
    b.validate();
    FAIL() << "a pilot wider than the drill was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "Drill/Pilot diameter");
  }
  // Step drills: a leading section as wide as the drill, one shorter than its own point
  // (1.25 mm / tan 59° = 0.75 mm), a pilot hole wider than the leading section.
  const auto names = [](DrillBit b, const std::string& entry) {
    try {
      b.validate();
      ADD_FAILURE() << "accepted: " << b.describe();
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.where(), entry);
    }
  };
  DrillBit wide = step_drill();
  wide.step_diameter = 4e-3;
  names(wide, "Drill/Step drill/Leading diameter");
  DrillBit short_lead = step_drill();
  short_lead.step_length = 0.7e-3;
  names(short_lead, "Drill/Step drill/Leading length");
  names(step_drill(3e-3), "Drill/Pilot diameter");
  DrillingSchedule s;
  s.spindle_rpm = 0;
  try {
    s.validate();
    FAIL() << "a drill that does not turn was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "Drill/Spindle speed");
  }
}

// Thrust control through the entry: the point enters the bone with few lips engaged, so the
// feed that holds the thrust there is far larger than once the point is in. The feed of each
// sub-step is the one whose thrust at the sub-step's end (the most engaged point) is the
// target, taken on the side below it where one more lip sample engaging makes the thrust
// jump: neither the intervals (forces at the sub-steps' middles) nor the ends exceed the
// target, and once the point is in, the target is held to the bisection's tolerance.
TEST(DrillingProgramme, ThrustControlDoesNotOvershootAtTheEntry) {
  const CuttingCoefficients c = cortical();
  DrillingSchedule sched;
  sched.spindle_rpm = 1000;
  sched.feed_rate = 1e-3;
  sched.thrust_control = true;
  sched.thrust_force = 60;
  const DrillHole hole = downward_hole(4e-3);
  const DrillingProgramme programme(DrillingForceModel(bit()), {hole}, sched);
  const auto material = cortical_below_top;
  DrillState st = programme.initial_state();
  const DrillingForceModel model(bit());
  const auto in_bone = [&](double a, double, double) -> std::optional<CuttingCoefficients> {
    if (a < 0)
      return std::nullopt;
    return c;
  };
  double max_thrust = 0, max_end_thrust = 0;
  for (unsigned int step = 0; step < 400 && st.phase == DrillPhase::feed; ++step) {
    const DrillInterval I = programme.advance(st, 0.05, 8, material);
    max_thrust = std::max(max_thrust, I.max_thrust);
    // Also where the last sub-step ends, the point at its most engaged.
    max_end_thrust =
        std::max(max_end_thrust, model.load(st.tip, I.feed_per_rev, 1000, in_bone).thrust);
  }
  EXPECT_LE(max_end_thrust, 60.0 * (1 + 1e-6));
  EXPECT_NE(st.phase, DrillPhase::feed);
  EXPECT_NEAR(st.deepest[0], 4e-3, 1e-15);
  EXPECT_LE(max_thrust, 60.0 * (1 + 1e-6));
  // Fully engaged the thrust is held exactly (the bisection's tolerance).
  EXPECT_GE(max_thrust, 60.0 * (1 - 1e-6));
}
