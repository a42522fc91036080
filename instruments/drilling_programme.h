#ifndef SPINESIM_INSTRUMENTS_DRILLING_PROGRAMME_H
#define SPINESIM_INSTRUMENTS_DRILLING_PROGRAMME_H

// What the drill does over time: holes in sequence, each fed from its entry point to its
// depth (at a constant feed rate, or at the feed that holds a constant thrust), a dwell at
// depth, the retraction, and a pause before the next hole. With a peck depth the feed stops
// after each peck: the bit withdraws to the entry point (chips out, irrigation in) and
// returns down its own hole at the retraction speed, cutting nothing, before the next peck.
// advance() integrates a time interval in sub-steps, splitting them exactly where a phase ends, and
// returns the cutting and margin-friction energies of the interval, so heat input over any step is
// the integral of the power, not a sample of it.

#include "instruments/drilling_force_model.h"

#include <string>
#include <vector>

namespace spinesim::instruments {

struct DrillHole {
  HoleAxis axis;
  double depth = 10e-3; // tip travel from the entry point [m]
};

struct DrillingSchedule {
  double spindle_rpm = 1000;         // [rev/min]
  bool thrust_control = false;       // feed from Thrust force instead of Feed rate
  double feed_rate = 1e-3;           // [m/s]; with thrust control, the approach speed in air
  double thrust_force = 40;          // [N]
  double dwell = 0;                  // at depth, rotating [s]
  double retraction_speed = 5e-3;    // [m/s]
  double pause = 0;                  // after leaving a hole, before the next [s]
  double peck_depth = 0;             // tip travel per peck [m]; 0 = one continuous feed
  double margin_friction_torque = 0; // of the margins on the hole wall [N m]
  // InvalidInput naming the Drill entry: speed or feed not positive, negative times.
  void validate() const;
};

// The peck phases come last so that checkpoints written before them keep their numbers.
enum class DrillPhase { feed, dwell, retract, pause, done, peck_retract, peck_return };
std::string to_string(DrillPhase phase);

struct DrillState {
  unsigned int hole = 0;
  DrillPhase phase = DrillPhase::feed;
  double tip = 0;              // axial depth of the tip in the current hole [m]
  double phase_time = 0;       // time spent in the current phase [s]
  std::vector<double> deepest; // per hole, the deepest tip reached [m]
  double peck_start = 0;       // tip depth where the current peck's feed began [m]
  unsigned int pecks = 0;      // peck withdrawals so far, all holes [-]
};

struct DrillInterval {
  double cutting_energy = 0;             // ∫ (M ω + F v) dt [J]
  double torque_energy = 0;              // ∫ M ω dt [J], the lips' torque part of it
  double friction_energy = 0;            // ∫ M_margin ω dt while the drill is in its hole [J]
  double max_thrust = 0, max_torque = 0; // [N], [N m]
  double feed_per_rev = 0;               // at the end of the interval's last feeding sub-step [m]
  double time_in_bone = 0;               // of the interval, with the tip below its entry [s]
  // Tip depth at the end of the interval's last feeding sub-step: where the lips were when they
  // last cut (a peck or the feed may end mid-interval and the bit withdraw) [m].
  double cut_tip = 0;
};

class DrillingProgramme {
 public:
  // InvalidInput naming Drill/Peck depth for pecks under 1e-3 of a hole's depth (more than a
  // thousand pecks a hole).
  DrillingProgramme(DrillingForceModel model, std::vector<DrillHole> holes,
                    DrillingSchedule schedule);

  DrillState initial_state() const;
  // Advances `state` by dt in `substeps` equal parts (phase ends split them exactly);
  // material(hole, a, r, θ) gives the coefficients at a lip point of hole `hole`.
  DrillInterval advance(
      DrillState& state, double dt, unsigned int substeps,
      const std::function<std::optional<CuttingCoefficients>(unsigned int, double, double, double)>&
          material) const;
  // Time the programme takes with the feed rate (thrust control: an estimate at Feed rate) [s].
  double nominal_duration() const;
  // Speed of the tip while feeding at Feed rate [m/s] (the time step follows it).
  double feed_speed() const { return schedule_.feed_rate; }
  const std::vector<DrillHole>& holes() const { return holes_; }
  const DrillingSchedule& schedule() const { return schedule_; }
  const DrillingForceModel& model() const { return model_; }

 private:
  DrillingForceModel model_;
  std::vector<DrillHole> holes_;
  DrillingSchedule schedule_;
};

} // namespace spinesim::instruments

#endif
