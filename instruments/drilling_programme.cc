#include "instruments/drilling_programme.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>

namespace spinesim::instruments {

void DrillingSchedule::validate() const {
  if (!(spindle_rpm > 0) || !std::isfinite(spindle_rpm))
    throw InvalidInput("Drill/Spindle speed", std::to_string(spindle_rpm),
                       "a positive speed [rev/min]: a drill that does not turn cannot feed");
  if (!(feed_rate > 0) || !std::isfinite(feed_rate))
    throw InvalidInput("Drill/Feed rate", std::to_string(feed_rate * 1e3),
                       "a positive feed rate [mm/s]");
  if (thrust_control && !(thrust_force > 0))
    throw InvalidInput("Drill/Thrust force", std::to_string(thrust_force),
                       "a positive thrust [N] with Feed control = thrust");
  if (!(dwell >= 0))
    throw InvalidInput("Drill/Dwell", std::to_string(dwell), "a time >= 0 [s]");
  if (!(retraction_speed > 0))
    throw InvalidInput("Drill/Retraction speed", std::to_string(retraction_speed * 1e3),
                       "a positive speed [mm/s]");
  if (!(pause >= 0))
    throw InvalidInput("Drill/Pause between holes", std::to_string(pause), "a time >= 0 [s]");
  if (!(peck_depth >= 0) || !std::isfinite(peck_depth))
    throw InvalidInput("Drill/Peck depth", std::to_string(peck_depth * 1e3),
                       "a depth >= 0 [mm] (0: one continuous feed)");
  if (!(margin_friction_torque >= 0))
    throw InvalidInput("Drill/Margin friction torque", std::to_string(margin_friction_torque * 1e3),
                       "a torque >= 0 [N mm]");
}

std::string to_string(DrillPhase phase) {
  switch (phase) {
  case DrillPhase::feed:
    return "feed";
  case DrillPhase::dwell:
    return "dwell";
  case DrillPhase::retract:
    return "retract";
  case DrillPhase::pause:
    return "pause";
  case DrillPhase::done:
    return "done";
  case DrillPhase::peck_retract:
    return "peck_retract";
  case DrillPhase::peck_return:
    return "peck_return";
  }
  return "?";
}

DrillingProgramme::DrillingProgramme(DrillingForceModel model, std::vector<DrillHole> holes,
                                     DrillingSchedule schedule)
    : model_(std::move(model)), holes_(std::move(holes)), schedule_(schedule) {
  schedule_.validate();
  // Clinical pecks are 0.5-2 mm on holes of 5-40 mm; a thousand a hole bounds the work.
  for (const auto& h : holes_)
    if (schedule_.peck_depth > 0 && schedule_.peck_depth < 1e-3 * h.depth)
      throw InvalidInput("Drill/Peck depth", std::to_string(schedule_.peck_depth * 1e3) + " mm",
                         "0 (no pecks) or at least 1e-3 of the hole's depth (" +
                             std::to_string(h.depth * 1e-3 * 1e3) + " mm)");
}

DrillState DrillingProgramme::initial_state() const {
  DrillState s;
  s.deepest.assign(holes_.size(), 0.0);
  if (holes_.empty())
    s.phase = DrillPhase::done;
  return s;
}

double DrillingProgramme::nominal_duration() const {
  double t = 0;
  for (const auto& h : holes_) {
    t += h.depth / schedule_.feed_rate + schedule_.dwell + h.depth / schedule_.retraction_speed +
         schedule_.pause;
    // Each peck ending above the full depth withdraws to the entry and comes back.
    for (double d = schedule_.peck_depth; schedule_.peck_depth > 0 && d < h.depth * (1 - 1e-12);
         d += schedule_.peck_depth)
      t += 2 * d / schedule_.retraction_speed;
  }
  return t;
}

DrillInterval DrillingProgramme::advance(
    DrillState& st, double dt, unsigned int substeps,
    const std::function<std::optional<CuttingCoefficients>(unsigned int, double, double, double)>&
        material) const {
  DrillInterval out;
  const double omega = 2 * pi * schedule_.spindle_rpm / 60.0;
  const double h = dt / std::max(1u, substeps);
  double left = dt;
  for (unsigned int k = 0; k < std::max(1u, substeps) && st.phase != DrillPhase::done; ++k) {
    double sub = std::min(h, left);
    left -= sub;
    if (k + 1 == std::max(1u, substeps))
      sub += left, left = 0; // round-off of the division goes to the last part
    while (sub > 0 && st.phase != DrillPhase::done) {
      const DrillHole& hole = holes_[st.hole];
      const unsigned int hole_index = st.hole;
      const auto mat = [&](double a, double r, double theta) {
        return material(hole_index, a, r, theta);
      };
      double used = sub;
      const DrillPhase phase_before = st.phase;
      const double tip_before = st.tip;
      switch (st.phase) {
      case DrillPhase::feed: {
        // The feed over the part: at Feed rate, or under thrust control the one whose thrust at
        // the part's end, the most engaged point of the part, is the Thrust force (taken on
        // the side at or below it: the thrust jumps as one more lip sample engages). The feed
        // holding it at the part's start bounds it from above. Taken at the start, a point
        // entering the bone with few lips engaged ran away (60 N gave 650 N by the end of the
        // first step). Where no lip cuts yet, the bit approaches at the Feed rate.
        // This peck ends at its depth, or at the hole's.
        const bool pecking = schedule_.peck_depth > 0 &&
                             st.peck_start + schedule_.peck_depth < hole.depth * (1 - 1e-12);
        const double stop = pecking ? st.peck_start + schedule_.peck_depth : hole.depth;
        double f = schedule_.feed_rate * 60.0 / schedule_.spindle_rpm;
        if (schedule_.thrust_control) {
          const double rev = schedule_.spindle_rpm / 60.0, F = schedule_.thrust_force;
          const double start =
              model_.feed_for_thrust(st.tip, F, schedule_.spindle_rpm, mat, 100 * f);
          double hi = start > 0 ? start : f;
          const auto end_thrust = [&](double feed) {
            const double advance = std::min(feed * rev * sub, stop - st.tip);
            return model_.load(st.tip + advance, feed, schedule_.spindle_rpm, mat).thrust;
          };
          if (end_thrust(hi) > F * (1 + 1e-9)) {
            double lo = 0;
            while (hi - lo > 1e-9 * hi) {
              const double mid = 0.5 * (lo + hi);
              (end_thrust(mid) > F ? hi : lo) = mid;
            }
            hi = lo;
          }
          f = hi;
        }
        const double v = f * schedule_.spindle_rpm / 60.0;
        used = std::min(sub, std::max(0.0, stop - st.tip) / v);
        // Forces at the middle of the part (midpoint rule in time).
        const DrillingLoad L = model_.load(st.tip + 0.5 * v * used, f, schedule_.spindle_rpm, mat);
        out.cutting_energy += L.power * used;
        out.torque_energy += L.torque * omega * used;
        out.max_thrust = std::max(out.max_thrust, L.thrust);
        out.max_torque = std::max(out.max_torque, L.torque);
        out.feed_per_rev = f;
        st.tip = std::min(stop, st.tip + v * used);
        out.cut_tip = st.tip;
        if (st.tip >= stop - 1e-12 * hole.depth) {
          st.tip = stop;
          st.phase = pecking ? DrillPhase::peck_retract : DrillPhase::dwell;
          st.phase_time = 0;
          st.pecks += pecking ? 1 : 0;
        }
        break;
      }
      case DrillPhase::retract:
      case DrillPhase::peck_retract: // out to the entry point; then the pause, or the return
        used = std::min(sub, st.tip / schedule_.retraction_speed);
        st.tip -= schedule_.retraction_speed * used;
        if (st.tip <= 1e-12 * hole.depth) {
          st.tip = 0;
          st.phase = st.phase == DrillPhase::retract ? DrillPhase::pause : DrillPhase::peck_return;
          st.phase_time = 0;
        }
        break;
      case DrillPhase::peck_return: { // back down the hole cut so far; nothing to cut
        const double bottom = st.deepest[hole_index];
        used = std::min(sub, std::max(0.0, bottom - st.tip) / schedule_.retraction_speed);
        st.tip = std::min(bottom, st.tip + schedule_.retraction_speed * used);
        if (st.tip >= bottom - 1e-12 * hole.depth) {
          st.tip = bottom;
          st.peck_start = bottom;
          st.phase = DrillPhase::feed;
          st.phase_time = 0;
        }
        break;
      }
      case DrillPhase::dwell:
        used = std::min(sub, schedule_.dwell - st.phase_time);
        if (used <= 0) {
          used = 0;
          st.phase = DrillPhase::retract;
          st.phase_time = 0;
        }
        break;
      case DrillPhase::pause:
        used = std::min(sub, schedule_.pause - st.phase_time);
        if (used <= 0) {
          used = 0;
          ++st.hole;
          st.tip = 0;
          st.peck_start = 0;
          st.phase = st.hole < holes_.size() ? DrillPhase::feed : DrillPhase::done;
          st.phase_time = 0;
        }
        break;
      case DrillPhase::done:
        break;
      }
      if (st.phase != DrillPhase::done && hole_index < holes_.size())
        st.deepest[hole_index] = std::max(st.deepest[hole_index], st.tip);
      // Margin friction while the bit turns in its hole (feed, dwell, retraction).
      if (used > 0 && (st.tip > 0 || tip_before > 0)) {
        out.friction_energy += schedule_.margin_friction_torque * omega * used;
        out.time_in_bone += used;
      }
      if (st.phase == phase_before)
        st.phase_time += used;
      sub -= used;
    }
  }
  return out;
}

} // namespace spinesim::instruments
