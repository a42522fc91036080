#ifndef SPINESIM_APPLICATIONS_SIMULATION_CRACK_PATH_H
#define SPINESIM_APPLICATIONS_SIMULATION_CRACK_PATH_H

// Generic crack output of a run with particles, whatever the crack's direction:
// crack_path.csv lists every particle whose damage reached `Damage threshold`, with its
// reference position, its damage and the time it first reached the threshold (at history
// resolution). A scene whose crack should follow a known line asks for figures along it with
// `Crack line` (e.g. "x, y = 0": the extent along x and the RMS deviation from y = 0);
// nothing in the scenario knows any particular scene. Every run with cracked particles gets the
// direction-free figures of add_direction_figures().

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace spinesim::framework {
class Summary;
}

namespace spinesim::applications {

struct CrackOutputParameters {
  double damage_threshold = 0.35; // φ at which a particle counts as cracked [-]
  std::string crack_line;         // "<along>, <across> = <value>", empty = no line figures

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class CrackPath {
 public:
  // InvalidInput naming Simulation/Crack line if it cannot be read for this dimension.
  explicit CrackPath(const CrackOutputParameters& parameters);

  // Every function below names particle i by keys[i] when `keys` is given (a distributed
  // zone's lattice ids, unique over the ranks), by i otherwise.
  //
  // Notes the particles (those with `counted` set) whose damage reached the threshold by
  // `time`; the first time is kept.
  void update(const std::vector<dealii::Point<dim>>& positions, const std::vector<double>& damage,
              const std::vector<std::uint8_t>& counted, double time,
              const std::vector<std::uint64_t>* keys = nullptr);
  // x, y[, z] (reference position), damage now, failure time, one row per cracked particle of
  // any rank (collective; `damage` current, on every rank, for every particle that reached the
  // threshold).
  std::string csv(const std::vector<dealii::Point<dim>>& positions,
                  const std::vector<double>& damage, MPI_Comm comm,
                  const std::vector<std::uint64_t>* keys = nullptr) const;
  double damage_threshold() const { return prm_.damage_threshold; }
  // With a crack line: crack_extent_min_<along>_m, crack_extent_max_<along>_m and
  // crack_path_rms_<across>_m over the counted particles at or past the threshold now.
  // Collective (the grown_crack_ figures need every rank's failure times).
  void add_figures(framework::Summary& summary, const std::vector<dealii::Point<dim>>& positions,
                   const std::vector<double>& damage, const std::vector<std::uint8_t>& counted,
                   MPI_Comm comm, const std::vector<std::uint64_t>* keys = nullptr) const;
  // Whatever the crack's direction: crack_particles, and for two or more cracked particles
  // crack_angle_deg (principal axis of the cracked particles in the x-y plane, from the x
  // axis, in (−90, 90]), crack_length_m along it and the tips crack_tip_{1,2}_<axis>_m. The
  // same with the prefix grown_crack_ over the particles that cracked during the run (not at
  // t = 0 by a pre-crack): the direction a crack took from its notch.
  void add_direction_figures(framework::Summary& summary,
                             const std::vector<dealii::Point<dim>>& positions,
                             const std::vector<double>& damage,
                             const std::vector<std::uint8_t>& counted, MPI_Comm comm,
                             const std::vector<std::uint64_t>* keys = nullptr) const;
  // Failure times of every rank (collective), for checkpoints; from_json takes them all.
  nlohmann::json to_json(MPI_Comm comm) const;
  void from_json(const nlohmann::json& j);

 private:
  CrackOutputParameters prm_;
  void direction_figures(framework::Summary& summary, const std::string& prefix,
                         const std::vector<dealii::Point<dim>>& cracked) const;
  int along_ = -1, across_ = -1;                 // coordinate indices of the crack line, -1 = none
  double offset_ = 0;                            // the line's value of the across coordinate [m]
  std::map<std::uint64_t, double> failure_time_; // particle -> first time at threshold [s]
  // The failure times of all ranks (the earliest where two ranks saw the same particle).
  std::map<std::uint64_t, double> gathered(MPI_Comm comm) const;
};

} // namespace spinesim::applications

#endif
