#include "fem/heat/moving_heat_source.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <deal.II/base/utilities.h>

#include <cmath>
#include <limits>

namespace spinesim::fem {

template <int dim>
MovingHeatSource<dim>::MovingHeatSource(std::vector<dealii::Point<dim>> path, double speed,
                                        double power, double radius, double start_time,
                                        double end_time, const std::string& where)
    : path_(std::move(path)), speed_(speed), power_(power), radius_(radius),
      start_time_(start_time),
      end_time_(end_time < 0 ? std::numeric_limits<double>::max() : end_time) {
  if (path_.empty())
    throw InvalidInput(where + "/Path", "the path has no points", "at least one point");
  if (!(radius_ > 0) || !std::isfinite(radius_))
    throw InvalidInput(where + "/Radius", "radius " + std::to_string(radius_),
                       "a positive length [m]");
  if (!(speed_ >= 0) || !std::isfinite(speed_))
    throw InvalidInput(where + "/Speed", "speed " + std::to_string(speed_), "a speed >= 0 [m/s]");
  if (!(power_ >= 0) || !std::isfinite(power_))
    throw InvalidInput(where + "/Power", "power " + std::to_string(power_), "a power >= 0 [W]");
  if (end_time_ < start_time_)
    throw InvalidInput(where + "/End time", "the source ends before it starts",
                       "End time >= Start time, or a negative End time (never off)");
  cumulative_.push_back(0.0);
  for (unsigned int i = 1; i < path_.size(); ++i)
    cumulative_.push_back(cumulative_.back() + path_[i].distance(path_[i - 1]));
  length_ = cumulative_.back();
}

template <int dim>
bool MovingHeatSource<dim>::active(double time) const {
  return power_ > 0 && time >= start_time_ && time <= end_time_;
}

template <int dim>
dealii::Point<dim> MovingHeatSource<dim>::position(double time) const {
  const double s = speed_ * std::max(0.0, time - start_time_);
  if (s >= length_)
    return path_.back();
  unsigned int i = 1;
  while (i + 1 < path_.size() && cumulative_[i] < s)
    ++i;
  const double segment = cumulative_[i] - cumulative_[i - 1];
  const double w = segment > 0 ? (s - cumulative_[i - 1]) / segment : 1.0;
  return path_[i - 1] + w * (path_[i] - path_[i - 1]);
}

template <int dim>
double MovingHeatSource<dim>::density(const dealii::Point<dim>& x, double time) const {
  return density_about(x, position(time));
}

template <int dim>
double MovingHeatSource<dim>::density_about(const dealii::Point<dim>& x,
                                            const dealii::Point<dim>& centre) const {
  const double r2 = radius_ * radius_;
  return std::exp(-x.distance_square(centre) / r2) / std::pow(M_PI * r2, 0.5 * dim);
}

template <int dim>
std::vector<dealii::Point<dim>> MovingHeatSource<dim>::parse_path(const std::string& text,
                                                                  const std::string& where) {
  std::vector<dealii::Point<dim>> points;
  const auto flat = parse_point_list(text, where, dim);
  for (std::size_t k = 0; k + dim <= flat.size(); k += dim) {
    dealii::Point<dim> p;
    for (unsigned int d = 0; d < dim; ++d)
      p[d] = flat[k + d];
    points.push_back(p);
  }
  if (points.empty())
    throw InvalidInput(where, "the path is empty", "at least one point 'x,y[,z]'");
  return points;
}

template class MovingHeatSource<2>;
template class MovingHeatSource<3>;

} // namespace spinesim::fem
