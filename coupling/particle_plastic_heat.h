#ifndef SPINESIM_COUPLING_PARTICLE_PLASTIC_HEAT_H
#define SPINESIM_COUPLING_PARTICLE_PLASTIC_HEAT_H

// The plastic work of the free particles (ParticleMethod::plastic_work_density × volume), of
// which the Taylor–Quinney coefficient β turns into heat, handed to the FEM heat equation as a
// source in each particle's host cell, as the FEM's own plastic work is (Taylor & Quinney
// 1934; Simo & Miehe 1992, CMAME 98, eq. 2.12 with the dissipation rate β D_p). A particle's
// work counts from the moment it became free: what it inherited at conversion was the FEM
// cell's plastic work, which heated the FEM there, and a ghost's follows the FEM.

#include "coupling/coupling_state.h"

#include <deal.II/lac/vector.h>

#include <cstdint>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class ParticlePlasticHeat {
 public:
  explicit ParticlePlasticHeat(CouplingState<dim>& state) : state_(state) {}

  // Takes the baseline of particles new since the last call and of ghosts that became free
  // (their inherited work), and re-takes it for ghosts. Called once conversions have handed
  // their states over; nothing to do without a heat solver or plastic history.
  void track_new_particles();
  // β × the plastic work done since the last call as a power density [W/m^3] over `elapsed`
  // [s], one entry per active cell (locally owned host cells; others 0). Collective.
  dealii::Vector<double> take(double beta, double elapsed);
  double heat() const { return heat_; } // handed to the FEM so far [J], global
  double work() const { return work_; } // plastic work of free particles counted so far [J]
  // After a checkpoint: the totals saved, the baselines of the particles as loaded (a
  // checkpoint is written after the step's heat was taken, so nothing is pending).
  void restore(double heat, double work);
  // Bytes of the per-particle arrays [B].
  std::size_t memory_bytes() const {
    return booked_.capacity() * sizeof(double) + free_.capacity();
  }

 private:
  // Per particle: its plastic work now [J] (0 for a method without plastic history).
  std::vector<double> current_work() const;
  // The baselines of new particles, of ghosts turned free and of ghosts, from the work `w`.
  void take_baselines(const std::vector<double>& w);
  CouplingState<dim>& state_;
  std::vector<double> booked_;     // per particle: plastic work already counted [J]
  std::vector<std::uint8_t> free_; // per particle: free when its baseline was taken
  double heat_ = 0, work_ = 0;
};

} // namespace spinesim::coupling

#endif
