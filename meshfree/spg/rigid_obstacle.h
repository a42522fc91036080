#ifndef SPINESIM_MESHFREE_SPG_RIGID_OBSTACLE_H
#define SPINESIM_MESHFREE_SPG_RIGID_OBSTACLE_H

// A rigid body the particles cannot enter: a half-space (plane), an infinite cylinder (a
// circle in 2-D) or a sphere, moving with a constant velocity. The body occupies
//   plane:    (x − p)·n < 0            (n points out of the obstacle, into the free side)
//   cylinder: dist(x, axis) < R        (axis through p along `axis`; 2-D: a disc)
//   sphere:   |x − p| < R
// gap(x) is the signed distance to the surface (> 0 outside) and normal(x) the outward unit
// normal there. Contact itself (frictionless penalty) is in SPGSolver.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <string>

namespace spinesim::meshfree {

template <int dim>
class RigidObstacle {
 public:
  enum class Shape { plane, cylinder, sphere };

  static RigidObstacle plane(const dealii::Point<dim>& point, const dealii::Tensor<1, dim>& normal);
  static RigidObstacle cylinder(const dealii::Point<dim>& point, const dealii::Tensor<1, dim>& axis,
                                double radius);
  static RigidObstacle sphere(const dealii::Point<dim>& centre, double radius);

  Shape shape() const { return shape_; }
  void set_velocity(const dealii::Tensor<1, dim>& v) { velocity_ = v; }
  const dealii::Tensor<1, dim>& velocity() const { return velocity_; }
  // Reference point at time t: p + v t.
  dealii::Point<dim> position(double time) const { return point_ + time * velocity_; }

  // Signed distance [m] and outward normal at x, at time t.
  double gap(const dealii::Point<dim>& x, double time, dealii::Tensor<1, dim>& normal) const;

 private:
  Shape shape_ = Shape::plane;
  dealii::Point<dim> point_;
  dealii::Tensor<1, dim> direction_; // plane normal or cylinder axis (unit)
  double radius_ = 0;
  dealii::Tensor<1, dim> velocity_;
};

} // namespace spinesim::meshfree

#endif
