#ifndef SPINESIM_COUPLING_PARTICLE_ZONE_H
#define SPINESIM_COUPLING_PARTICLE_ZONE_H

// The particle side of the `simulation` scenario: a body of particles on a lattice region, run
// by the particle method the scene names (meshfree/particle_method.h), loaded through prescribed
// displacements of particle regions, with pre-cracks, advanced explicitly (velocity Verlet,
// sub-stepped at the stable step) or quasi-statically (adaptive dynamic relaxation at every step).
//
// MPI: a zone on several ranks is distributed (zone_partition.h): each rank holds the particles
// of its p4est background cells and, as fixed ghosts refreshed before every force pass, those
// within two search radii. Bond-based PD keeps rows for owned particles only (the second ghost
// layer served the first layer's surface correction); NOSB-PD also keeps the first-layer
// ghosts' rows, so their families, which an owned particle's force gathers, are whole, and
// updates them as their owners do. Every sum over particles counts the owned ones, so it counts
// each particle once over the ranks (dynamic relaxation's sums included), and each rank writes
// its part of the output and checkpoint.

#include "fem/explicit_energy.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/parameter_handler.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::framework {
class RunContext;
}

namespace spinesim::applications {

using framework::RunContext;

struct ParticleZoneParameters {
  static constexpr unsigned int n_region_slots = 6;
  static constexpr unsigned int n_crack_slots = 4;

  struct Region {
    std::vector<double> lower, upper; // box corners [m]
    // Optional r1, r2: only the box's particles with r1 <= r <= r2 from the zone's centre (r in
    // the x-y plane, as for Shape = annulus) [m]; empty = the whole box.
    std::vector<double> radial_range;
    std::string components; // "x,y"
    std::string values;     // one expression per component, ';'-separated [m]
  };

  std::vector<double> lower{-0.5, -0.5, -0.5}, upper{0.5, 0.5, 0.5};
  double spacing = 0.05; // [m]
  // The lattice points of the box kept: all (box), those with inner <= r <= outer from the
  // centre, r in the x-y plane (annulus; 3-D: a tube along z) or in space (spherical_shell).
  std::string shape = "box";
  std::vector<double> centre{0, 0, 0};       // [m]
  double inner_radius = 0, outer_radius = 0; // [m]
  std::string initial_velocity; // dim ';'-separated expressions in x, y, z; empty = at rest
  std::string integration = "explicit";
  double time_step_safety = 0.8;
  double damping = 0;              // [1/s]
  std::vector<Region> regions;     // used slots only
  std::vector<std::string> cracks; // corners per crack (read per dimension)
  int reaction_region = -1;        // 1-based region whose reaction is reported

  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

template <int dim>
class ParticleZone {
 public:
  // Reads the "Particles" and "Material" sections (prm is the whole scene) and makes the
  // particle method `method` (a registered name) from its subsection of "Particles".
  ParticleZone(dealii::ParameterHandler& prm, const std::string& method, bool damage);
  ~ParticleZone();

  // Explicit integration only (InvalidInput otherwise); before setup().
  void set_energy_account(bool on);
  void setup(RunContext& ctx);
  // Advances from the zone's time to `time` [s]. Explicit: before each sub-step, `stop` (given
  // the zone's time [s]) may end the call early at a complete sub-step; returns whether `time`
  // was reached. `stop` is called on every rank at the same sub-steps.
  bool advance_to(double time, const std::function<bool(double)>& stop = {});
  // Quasi-static step cuts (Particles/Quasi-static/Step cuts): the sub-step the next step starts
  // with [s] (0: the whole step), the converged sub-steps since the last cut or growth, and the
  // cuts so far; a checkpoint keeps them, so a restart steps as the uninterrupted run.
  std::array<double, 3> step_cut_state() const;
  void restore_step_cut_state(const std::array<double, 3>& state);
  // The method's messages for the run log since the last call (e.g. particles that lost their
  // family), from every rank, on rank 0 (collective when distributed; empty elsewhere).
  std::vector<std::string> take_messages();

  // Updates the particles' damage, then adds the zone's columns.
  void add_history(std::vector<std::pair<std::string, double>>& row);
  void add_figures(RunContext& ctx) const;
  // The energy account at the end of the last step (zone_energy.h); not valid before one.
  fem::EnergyBalance energy_balance() const;
  // After load(): whether the checkpoint held the account (older ones do not).
  bool energy_account_restored() const;
  std::size_t n_bonds() const;     // bonds, each counted once
  double stable_time_step() const; // of its explicit steps [s]
  // The particles this rank holds (damage as of the last add_history): the whole zone, or in a
  // distributed zone its owned particles followed by its ghosts.
  const meshfree::ParticleSet<dim>& particles() const;
  // Their physical displacements [m] (SPG's unknowns are RK coefficients; the other methods'
  // are the displacements themselves).
  std::vector<dealii::Tensor<1, dim>> physical_displacements() const;
  // The force the supports of Particles/Reaction region exert (the negative of the internal
  // force on its prescribed particles, summed over the ranks; collective when distributed)
  // [N, N/m in 2-D]; zero without a reaction region.
  dealii::Tensor<1, dim> reaction() const;
  bool has_reaction() const;
  bool distributed() const;
  // Whether this rank owns particle i (always, unless distributed).
  bool is_owned(unsigned int i) const;
  // Lattice ids of particles() in a distributed zone (unique over the ranks); nullptr otherwise.
  const std::vector<std::uint64_t>* global_ids() const;
  std::uint64_t n_global_particles() const;
  // Bytes of particle data this rank holds: particles, bonds, the method's per-particle and
  // per-bond arrays, the partition's exchange vectors.
  std::size_t memory_bytes() const;
  // Writes particles_<cycle>.vtu (not distributed: call on rank 0) or, distributed (call on
  // every rank), one piece per rank and the .pvtu joining them; returns the file to record.
  std::string write_output(const std::string& directory, unsigned int cycle) const;

  // Not distributed: rank 0 writes `file`; distributed: every rank writes file.<rank>.
  void save(const std::string& file) const;
  void load(const std::string& file); // every rank reads

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

} // namespace spinesim::applications

#endif
