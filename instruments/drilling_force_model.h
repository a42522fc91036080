#ifndef SPINESIM_INSTRUMENTS_DRILLING_FORCE_MODEL_H
#define SPINESIM_INSTRUMENTS_DRILLING_FORCE_MODEL_H

// Mechanistic drilling forces: thrust, torque and cutting power of a two-lip twist (or step) drill
// from its feed per revolution, in the specific-cutting-force form of Kienzle (1952) used for bone
// by the mechanistic drilling models of Lee, Gozen & Ozdoganlar (2012, J. Biomech. 45:1076).
//
// Each lip is a straight cutting edge at its half angle κ (the point's; a step drill's shoulder
// has its own, DrillBit). At radius r the uncut chip
// is h = (f/2) sin κ thick and dr / sin κ wide (f the feed per revolution, shared by the
// two lips), so per lip the cutting force is K_c(h) h dr / sin κ and the edge-normal force
// K_t(h) h dr / sin κ, whose axial part is × sin κ. Summed over both lips:
//   dM = K_c(h) f r dr,          dF = K_t(h) f sin κ dr,
// with the size effect K(h) = K_ref (h / h_ref)^(−m) (thinner chips cost more energy per
// volume). Integrated by the midpoint rule over the lip samples that lie in bone (the pilot
// hole, air above the surface and holes already drilled cut nothing), each with its own
// material, averaged over the circle each lip sample sweeps in a revolution (the lips turn
// many times in a step). Cutting power P = M ω + F v_f (ω = 2π n / 60, v_f = f n / 60).
// The chisel edge is not modelled (it adds thrust, not torque; Lee et al. 2012 treat it as
// indentation): thrusts are those of the lips, a lower bound without a pilot hole.

#include "instruments/drill_bit.h"

#include <functional>
#include <optional>

namespace spinesim::instruments {

struct CuttingCoefficients {
  double tangential = 200e6;                 // K_c at h_ref [Pa] (N/mm² × 1e6)
  double thrust = 300e6;                     // K_t at h_ref [Pa]
  double exponent = 0.3;                     // m [-], 0 <= m < 1
  double reference_chip_thickness = 0.05e-3; // h_ref [m]
  double tangential_at(double h) const;
  double thrust_at(double h) const;
};

struct DrillingLoad {
  double torque = 0;           // M [N m]
  double thrust = 0;           // F [N]
  double power = 0;            // M ω + F v_f [W]
  double engaged_fraction = 0; // share of the lip samples (radius × azimuth) in bone [-]
};

class DrillingForceModel {
 public:
  // The coefficients of the bone at the lip point (axial a, radius r, azimuth θ about the
  // hole's axis) of the current hole, or none where that point is in no bone.
  using MaterialAt =
      std::function<std::optional<CuttingCoefficients>(double a, double r, double theta)>;

  // Each lip sample's coefficients are averaged over `azimuth_samples` equally spaced azimuths:
  // a time step spans many revolutions, so a lip element cuts, per revolution, whatever lies
  // on its circle (bone on part of it, a CT block's density varying round it).
  explicit DrillingForceModel(DrillBit bit, unsigned int lip_samples = 64,
                              unsigned int azimuth_samples = 16);

  // Forces with the tip at axial depth `tip`, feed `feed_per_rev` [m], speed [rev/min].
  DrillingLoad load(double tip, double feed_per_rev, double spindle_rpm,
                    const MaterialAt& material) const;
  // The feed per revolution giving the thrust `thrust` [N] (the thrust grows monotonically
  // with the feed), at most `max_feed`; 0 when no lip cuts.
  double feed_for_thrust(double tip, double thrust, double spindle_rpm, const MaterialAt& material,
                         double max_feed) const;
  const DrillBit& bit() const { return bit_; }

 private:
  DrillBit bit_;
  unsigned int samples_, azimuths_;
};

} // namespace spinesim::instruments

#endif
