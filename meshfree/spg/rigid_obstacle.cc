#include "meshfree/spg/rigid_obstacle.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::meshfree {

template <int dim>
RigidObstacle<dim> RigidObstacle<dim>::plane(const dealii::Point<dim>& point,
                                             const dealii::Tensor<1, dim>& normal) {
  if (!(normal.norm() > 0.0))
    throw InvalidInput("Contact/Normal", "zero normal", "a non-zero vector");
  RigidObstacle o;
  o.shape_ = Shape::plane;
  o.point_ = point;
  o.direction_ = normal / normal.norm();
  return o;
}

template <int dim>
RigidObstacle<dim> RigidObstacle<dim>::cylinder(const dealii::Point<dim>& point,
                                                const dealii::Tensor<1, dim>& axis, double radius) {
  if (!(radius > 0.0))
    throw InvalidInput("Contact/Radius", "= " + std::to_string(radius), "> 0 [m]");
  if (dim == 3 && !(axis.norm() > 0.0))
    throw InvalidInput("Contact/Axis", "zero axis", "a non-zero vector");
  RigidObstacle o;
  o.shape_ = Shape::cylinder;
  o.point_ = point;
  if (dim == 3)
    o.direction_ = axis / axis.norm();
  o.radius_ = radius;
  return o;
}

template <int dim>
RigidObstacle<dim> RigidObstacle<dim>::sphere(const dealii::Point<dim>& centre, double radius) {
  if (!(radius > 0.0))
    throw InvalidInput("Contact/Radius", "= " + std::to_string(radius), "> 0 [m]");
  RigidObstacle o;
  o.shape_ = Shape::sphere;
  o.point_ = centre;
  o.radius_ = radius;
  return o;
}

template <int dim>
double RigidObstacle<dim>::gap(const dealii::Point<dim>& x, double time,
                               dealii::Tensor<1, dim>& normal) const {
  const dealii::Tensor<1, dim> r = x - position(time);
  if (shape_ == Shape::plane) {
    normal = direction_;
    return r * direction_;
  }
  dealii::Tensor<1, dim> radial = r;
  if (shape_ == Shape::cylinder && dim == 3)
    radial -= (r * direction_) * direction_;
  const double d = radial.norm();
  if (d > 0.0)
    normal = radial / d;
  else {
    normal = 0;
    normal[0] = 1.0; // on the axis/centre: any direction
  }
  return d - radius_;
}

template class RigidObstacle<2>;
template class RigidObstacle<3>;

} // namespace spinesim::meshfree
