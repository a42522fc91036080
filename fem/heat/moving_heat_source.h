#ifndef SPINESIM_FEM_HEAT_MOVING_HEAT_SOURCE_H
#define SPINESIM_FEM_HEAT_MOVING_HEAT_SOURCE_H

// The drill-bit heat source: a Gaussian volumetric source of total power P moving at constant
// speed along a polyline. Between `start_time` and `end_time` the centre travels the path from
// its first point and then rests at its last point.

#include <deal.II/base/point.h>

#include <string>
#include <vector>

namespace spinesim::fem {

template <int dim>
class MovingHeatSource {
 public:
  // Throws InvalidInput (naming `where`) for an empty path, a non-positive radius, a negative
  // speed or power, or end_time < start_time (a negative end_time means "never switches off").
  MovingHeatSource(std::vector<dealii::Point<dim>> path, double speed, double power, double radius,
                   double start_time, double end_time, const std::string& where);

  bool active(double time) const;
  // Centre of the source at `time` (the first point before it starts moving).
  dealii::Point<dim> position(double time) const;
  // Gaussian density exp(-|x-c|^2/r^2) / (pi^(dim/2) r^dim) [1/m^dim]; it integrates to 1 over
  // R^dim. The solver rescales it on the mesh so that exactly `power` enters the body while at
  // least a fifth of the Gaussian lies inside (centre inside, on a face, or on a 2-D corner /
  // 3-D edge: the bit's heat goes into the bone it touches), fading beyond.
  double density(const dealii::Point<dim>& x, double time) const;
  // The same about a known centre (assembly loops compute position() once per time).
  double density_about(const dealii::Point<dim>& x, const dealii::Point<dim>& centre) const;
  // Distance beyond which density() is below 1e-11 of its peak: assembly skips cells further away.
  double cutoff_distance() const { return 5.0 * radius_; }

  double power() const { return power_; } // [W] (per unit depth [W/m] in 2-D)
  double radius() const { return radius_; }
  double path_length() const { return length_; }

  // Parses "x,y[,z]; x,y[,z]; ..." with exactly dim coordinates per point.
  static std::vector<dealii::Point<dim>> parse_path(const std::string& text,
                                                    const std::string& where);

 private:
  std::vector<dealii::Point<dim>> path_;
  std::vector<double> cumulative_; // arc length at each path point
  double speed_, power_, radius_, start_time_, end_time_, length_ = 0;
};

} // namespace spinesim::fem

#endif
