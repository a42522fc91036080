#ifndef SPINESIM_MESHFREE_PARTICLE_SET_H
#define SPINESIM_MESHFREE_PARTICLE_SET_H

// Particles as a structure of arrays: each field is one contiguous std::vector so the bond
// loops stream through memory. Per-particle accessors for setup code, whole arrays for loops.
//
// Conventions: `force` is the internal force on the particle [N] (force density times volume),
// `external_force` the applied one [N]; mass = density * volume. In 2-D every volume is an
// area times the out-of-plane thickness [m^3], so energies and forces are real 3-D quantities.
// Components flagged `fixed` are Dirichlet: integrators leave their displacement and velocity
// as the caller set them.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class ParticleSet {
 public:
  using Vector = dealii::Tensor<1, dim>;

  // `thickness` [m] is the out-of-plane thickness of a 2-D body (ignored, 1, in 3-D).
  explicit ParticleSet(double thickness = 1.0);

  // Lattice of centred cells in the box [lo, hi]: n_k = round((hi_k − lo_k)/h) cells per
  // direction (at least 1), spacing (hi_k − lo_k)/n_k (= h when the box is a multiple of h),
  // volume = product of spacings (times thickness in 2-D).
  static ParticleSet lattice(const dealii::Point<dim>& lo, const dealii::Point<dim>& hi, double h,
                             double thickness = 1.0);
  // Text file, one particle per line "x y [z] volume" (whitespace separated, '#' comments).
  // InvalidInput naming file:line on a malformed line or a non-positive volume.
  static ParticleSet from_file(const std::string& file_name, double thickness = 1.0);
  // Given points and volumes [m^3] (e.g. FEM quadrature points with JxW).
  static ParticleSet from_points(const std::vector<dealii::Point<dim>>& points,
                                 const std::vector<double>& volumes, double thickness = 1.0);

  // Appends a particle at rest with zero fields; returns its index.
  unsigned int add_particle(const dealii::Point<dim>& x, double volume);
  void reserve(unsigned int n);
  unsigned int size() const { return static_cast<unsigned int>(x_.size()); }
  double thickness() const { return thickness_; }

  // Per-particle access.
  const dealii::Point<dim>& reference_position(unsigned int i) const { return x_[i]; }
  dealii::Point<dim> current_position(unsigned int i) const { return x_[i] + u_[i]; }
  Vector& displacement(unsigned int i) { return u_[i]; }
  const Vector& displacement(unsigned int i) const { return u_[i]; }
  Vector& velocity(unsigned int i) { return v_[i]; }
  const Vector& velocity(unsigned int i) const { return v_[i]; }
  Vector& acceleration(unsigned int i) { return a_[i]; }
  const Vector& acceleration(unsigned int i) const { return a_[i]; }
  Vector& force(unsigned int i) { return f_[i]; }
  const Vector& force(unsigned int i) const { return f_[i]; }
  Vector& external_force(unsigned int i) { return fext_[i]; }
  const Vector& external_force(unsigned int i) const { return fext_[i]; }
  double& volume(unsigned int i) { return volume_[i]; }
  double volume(unsigned int i) const { return volume_[i]; }
  double& density(unsigned int i) { return density_[i]; }
  double density(unsigned int i) const { return density_[i]; }
  double mass(unsigned int i) const { return density_[i] * volume_[i]; }
  // Index into the particle method's MaterialTable (0 without one).
  unsigned int& material_id(unsigned int i) { return material_id_[i]; }
  unsigned int material_id(unsigned int i) const { return material_id_[i]; }
  const std::vector<unsigned int>& material_ids() const { return material_id_; }
  double& temperature(unsigned int i) { return temperature_[i]; }
  double temperature(unsigned int i) const { return temperature_[i]; }
  double& damage(unsigned int i) { return damage_[i]; }
  double damage(unsigned int i) const { return damage_[i]; }

  // Dirichlet flags: one bit per component.
  bool is_fixed(unsigned int i, unsigned int component) const {
    return (fixed_[i] >> component) & 1u;
  }
  bool is_fixed(unsigned int i) const { return fixed_[i] != 0; }
  bool is_fixed_in_every_component(unsigned int i) const { return fixed_[i] == (1u << dim) - 1u; }
  std::uint8_t fixed_mask(unsigned int i) const { return fixed_[i]; }
  void set_fixed(unsigned int i, unsigned int component, bool fixed = true);
  void set_fixed(unsigned int i, bool fixed = true); // all components

  // Characteristic spacing (V/T)^(1/2) in 2-D, V^(1/3) in 3-D [m].
  double spacing(unsigned int i) const;

  void set_density(double rho);
  double kinetic_energy() const; // ½ Σ m |v|² [J]
  // Bytes held by the arrays (capacity), scalar fields included.
  std::size_t memory_bytes() const;

  // Whole arrays, for loops.
  const std::vector<dealii::Point<dim>>& reference_positions() const { return x_; }
  std::vector<Vector>& displacements() { return u_; }
  const std::vector<Vector>& displacements() const { return u_; }
  std::vector<Vector>& velocities() { return v_; }
  const std::vector<Vector>& velocities() const { return v_; }
  std::vector<Vector>& accelerations() { return a_; }
  const std::vector<Vector>& accelerations() const { return a_; }
  std::vector<Vector>& forces() { return f_; }
  const std::vector<Vector>& forces() const { return f_; }
  std::vector<Vector>& external_forces() { return fext_; }
  const std::vector<Vector>& external_forces() const { return fext_; }
  const std::vector<double>& volumes() const { return volume_; }
  const std::vector<double>& densities() const { return density_; }
  std::vector<double>& damages() { return damage_; }
  const std::vector<double>& damages() const { return damage_; }
  std::vector<double>& temperatures() { return temperature_; }
  const std::vector<double>& temperatures() const { return temperature_; }
  const std::vector<std::uint8_t>& fixed_masks() const { return fixed_; }

  // Per-method scalar fields by name (e.g. "dilatation"), sized with the particles.
  // add_scalar_field returns the existing field if the name is taken. References stay valid
  // until particles are added.
  std::vector<double>& add_scalar_field(const std::string& name, double initial_value = 0.0);
  bool has_scalar_field(const std::string& name) const;
  std::vector<double>& scalar_field(const std::string& name);             // InvalidInput if absent
  const std::vector<double>& scalar_field(const std::string& name) const; // InvalidInput if absent
  std::vector<std::string> scalar_field_names() const;

 private:
  double thickness_;
  std::vector<dealii::Point<dim>> x_;
  std::vector<Vector> u_, v_, a_, f_, fext_;
  std::vector<double> volume_, density_, temperature_, damage_;
  std::vector<unsigned int> material_id_;
  std::vector<std::uint8_t> fixed_;
  std::map<std::string, std::vector<double>> scalar_fields_;
};

} // namespace spinesim::meshfree

#endif
