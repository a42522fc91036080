#ifndef SPINESIM_COUPLING_CHECKPOINT_TEXT_H
#define SPINESIM_COUPLING_CHECKPOINT_TEXT_H

// The bytes of a coupling checkpoint ("spinesim_coupling 1" to "9", written by
// CouplingCheckpoint::save) read into plain records, with every check a file from outside
// needs: counts bounded by the file's size before anything is sized by them, every record
// complete, in range and finite, nothing after the last record. No deal.II: the loader turns
// the records into particles, and the fuzz target (tests/fuzz) feeds it arbitrary bytes.

#include <array>
#include <cstddef>
#include <cstdint>
#include <istream>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::coupling {

// Numbers of one material state in a history record (materials::material_state_doubles; the
// loader checks that the two agree). Version 3 files hold one fewer: no fracture damage.
constexpr unsigned int checkpoint_state_doubles = 15;

// One particle's line: host cell (deal.II CellId text) and quadrature point, free flag,
// Dirichlet slots, volume, density, temperature, reference position, displacement, velocity
// (version 5) the support offset (the first `dim` entries of the arrays are used) and
// (version 6) the explicit integration's own state: the displacement at the last force pass
// (the energy account's u_{n−1}) and the particle's stiffness bound of the stable step (0:
// none), so a restart takes the steps and the account of the uninterrupted run.
struct CheckpointParticle {
  std::string cell;
  unsigned int point = 0;
  bool free = false;
  std::uint32_t fixed_slots = 0;
  double volume = 0, density = 0, temperature = 0;
  std::array<double, 3> position{}, displacement{}, velocity{}, support_offset{},
      last_pass_displacement{};
  double stiffness_bound = 0; // [N/m^4 or the method's unit]
  unsigned int material = 0;  // version 7: index into CheckpointContents::laws
};

// A particle law's parameters (materials::LawParameters, version 7): the model's name, the
// values in the order of checkpoint_law_values and the secant-tangent flag.
constexpr unsigned int checkpoint_law_values = 11;
struct CheckpointLaw {
  std::string model;
  std::array<double, checkpoint_law_values> values{};
  bool secant_tangent = false;
};

// The material history of the family of `particle` towards `neighbour`.
struct CheckpointHistory {
  unsigned int particle = 0, neighbour = 0;
  std::array<double, checkpoint_state_doubles> state{};
};

struct CheckpointContents {
  int version = 0;
  double time = 0, dissipation = 0, heat = 0;    // version 1: no fracture-heat totals
  std::map<std::string, unsigned int> converted; // cell id -> conversion batch
  std::vector<CheckpointParticle> particles;
  std::vector<std::pair<unsigned int, unsigned int>> broken; // particle index pairs
  std::vector<CheckpointHistory> history;                    // version 3
  std::size_t n_last_pass = 0;     // version 6: particles the last force pass saw (a prefix)
  std::vector<CheckpointLaw> laws; // version 7: the particles' laws (CouplingState::laws)
  // Version 8: the committed stick points of particles in frictional contact with an implant
  // (ImplantContact): particle index and the point (first `dim` entries used) [m].
  std::vector<std::pair<unsigned int, std::array<double, 3>>> sticks;
  // Version 9: the short-range pairs born closer than their reference contact distance
  // (meshfree/short_range_forces.h): particles i < j and the distance [m].
  struct Birth {
    unsigned int i = 0, j = 0;
    double reach = 0;
  };
  std::vector<Birth> births;
};

// Reads a checkpoint of a `dim`-dimensional run whose coupling has `n_points` candidate
// particle sites (quadrature points), from `in` holding `bytes` bytes. Throws InvalidInput
// naming `file` for anything save() would not have written.
CheckpointContents read_checkpoint_text(std::istream& in, std::uintmax_t bytes, unsigned int dim,
                                        std::size_t n_points, const std::string& file);

} // namespace spinesim::coupling

#endif
