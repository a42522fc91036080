#include "meshfree/particle_set.h"

#include "base/exceptions.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
ParticleSet<dim>::ParticleSet(double thickness) : thickness_(dim == 2 ? thickness : 1.0) {
  if (!(thickness > 0.0) || !std::isfinite(thickness))
    throw InvalidInput("ParticleSet thickness", "thickness = " + std::to_string(thickness),
                       "a positive finite thickness [m]");
}

template <int dim>
ParticleSet<dim> ParticleSet<dim>::lattice(const dealii::Point<dim>& lo,
                                           const dealii::Point<dim>& hi, double h,
                                           double thickness) {
  if (!(h > 0.0))
    throw InvalidInput("particle lattice", "spacing h = " + std::to_string(h), "h > 0 [m]");
  unsigned int n[dim];
  double dx[dim];
  double cell_volume = (dim == 2 ? thickness : 1.0);
  std::size_t total = 1;
  for (unsigned int d = 0; d < dim; ++d) {
    const double length = hi[d] - lo[d];
    if (!(length > 0.0))
      throw InvalidInput("particle lattice", "box with hi <= lo in direction " + std::to_string(d),
                         "hi > lo in every direction");
    n[d] = std::max<long>(1, std::lround(length / h));
    dx[d] = length / n[d];
    cell_volume *= dx[d];
    total *= n[d];
  }
  ParticleSet set(thickness);
  set.reserve(static_cast<unsigned int>(total));
  // x fastest: consecutive particles are spatial neighbours, which keeps the bond loops local.
  for (std::size_t c = 0; c < total; ++c) {
    std::size_t rest = c;
    dealii::Point<dim> p;
    for (unsigned int d = 0; d < dim; ++d) {
      const std::size_t k = rest % n[d];
      rest /= n[d];
      p[d] = lo[d] + (k + 0.5) * dx[d];
    }
    set.add_particle(p, cell_volume);
  }
  return set;
}

template <int dim>
ParticleSet<dim> ParticleSet<dim>::from_file(const std::string& file_name, double thickness) {
  std::ifstream in(file_name);
  if (!in)
    throw InvalidInput(file_name, "cannot open the particle file", "a readable text file");
  ParticleSet set(thickness);
  std::string line;
  unsigned int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto hash = line.find('#');
    if (hash != std::string::npos)
      line.erase(hash);
    std::istringstream fields(line);
    std::vector<double> values;
    double v;
    while (fields >> v)
      values.push_back(v);
    const std::string where = file_name + ":" + std::to_string(line_number);
    if (!fields.eof())
      throw InvalidInput(where, "a field is not a number", "numbers only: x y [z] volume");
    if (values.empty())
      continue;
    if (values.size() != dim + 1)
      throw InvalidInput(where, std::to_string(values.size()) + " fields",
                         std::to_string(dim + 1) +
                             " fields: " + (dim == 2 ? "x y volume" : "x y z volume"));
    dealii::Point<dim> p;
    for (unsigned int d = 0; d < dim; ++d)
      p[d] = values[d];
    if (!(values[dim] > 0.0) || !std::isfinite(values[dim]))
      throw InvalidInput(where, "volume " + std::to_string(values[dim]), "a positive volume [m^3]");
    set.add_particle(p, values[dim]);
  }
  return set;
}

template <int dim>
ParticleSet<dim> ParticleSet<dim>::from_points(const std::vector<dealii::Point<dim>>& points,
                                               const std::vector<double>& volumes,
                                               double thickness) {
  if (points.size() != volumes.size())
    throw InvalidInput("ParticleSet::from_points", "points and volumes differ in length",
                       "one volume per point");
  ParticleSet set(thickness);
  set.reserve(static_cast<unsigned int>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(volumes[i] > 0.0) || !std::isfinite(volumes[i]))
      throw InvalidInput("ParticleSet::from_points, point " + std::to_string(i),
                         "volume " + std::to_string(volumes[i]), "a positive volume [m^3]");
    set.add_particle(points[i], volumes[i]);
  }
  return set;
}

template <int dim>
unsigned int ParticleSet<dim>::add_particle(const dealii::Point<dim>& x, double volume) {
  x_.push_back(x);
  u_.emplace_back();
  v_.emplace_back();
  a_.emplace_back();
  f_.emplace_back();
  fext_.emplace_back();
  volume_.push_back(volume);
  density_.push_back(0.0);
  temperature_.push_back(0.0);
  damage_.push_back(0.0);
  material_id_.push_back(0);
  fixed_.push_back(0);
  for (auto& field : scalar_fields_)
    field.second.push_back(0.0);
  return size() - 1;
}

template <int dim>
void ParticleSet<dim>::reserve(unsigned int n) {
  x_.reserve(n);
  u_.reserve(n);
  v_.reserve(n);
  a_.reserve(n);
  f_.reserve(n);
  fext_.reserve(n);
  volume_.reserve(n);
  density_.reserve(n);
  temperature_.reserve(n);
  damage_.reserve(n);
  material_id_.reserve(n);
  fixed_.reserve(n);
}

template <int dim>
void ParticleSet<dim>::set_fixed(unsigned int i, unsigned int component, bool fixed) {
  const std::uint8_t bit = std::uint8_t(1u << component);
  fixed_[i] = fixed ? std::uint8_t(fixed_[i] | bit) : std::uint8_t(fixed_[i] & ~bit);
}

template <int dim>
void ParticleSet<dim>::set_fixed(unsigned int i, bool fixed) {
  fixed_[i] = fixed ? std::uint8_t((1u << dim) - 1u) : std::uint8_t(0);
}

template <int dim>
double ParticleSet<dim>::spacing(unsigned int i) const {
  return dim == 2 ? std::sqrt(volume_[i] / thickness_) : std::cbrt(volume_[i]);
}

template <int dim>
void ParticleSet<dim>::set_density(double rho) {
  if (!(rho > 0.0) || !std::isfinite(rho))
    throw InvalidInput("particle density", "density = " + std::to_string(rho),
                       "a positive density [kg/m^3]");
  std::fill(density_.begin(), density_.end(), rho);
}

template <int dim>
std::size_t ParticleSet<dim>::memory_bytes() const {
  std::size_t bytes =
      x_.capacity() * sizeof(dealii::Point<dim>) +
      (u_.capacity() + v_.capacity() + a_.capacity() + f_.capacity() + fext_.capacity()) *
          sizeof(Vector) +
      (volume_.capacity() + density_.capacity() + temperature_.capacity() + damage_.capacity()) *
          sizeof(double) +
      material_id_.capacity() * sizeof(unsigned int) + fixed_.capacity();
  for (const auto& [name, field] : scalar_fields_)
    bytes += field.capacity() * sizeof(double);
  return bytes;
}

template <int dim>
double ParticleSet<dim>::kinetic_energy() const {
  double e = 0;
  for (unsigned int i = 0; i < size(); ++i)
    e += 0.5 * mass(i) * v_[i].norm_square();
  return e;
}

template <int dim>
std::vector<double>& ParticleSet<dim>::add_scalar_field(const std::string& name,
                                                        double initial_value) {
  auto it = scalar_fields_.find(name);
  if (it != scalar_fields_.end())
    return it->second;
  return scalar_fields_.emplace(name, std::vector<double>(size(), initial_value)).first->second;
}

template <int dim>
bool ParticleSet<dim>::has_scalar_field(const std::string& name) const {
  return scalar_fields_.count(name) != 0;
}

template <int dim>
std::vector<double>& ParticleSet<dim>::scalar_field(const std::string& name) {
  auto it = scalar_fields_.find(name);
  if (it == scalar_fields_.end())
    throw InvalidInput("particle scalar field '" + name + "'", "no such field",
                       "a field registered with add_scalar_field");
  return it->second;
}

template <int dim>
const std::vector<double>& ParticleSet<dim>::scalar_field(const std::string& name) const {
  return const_cast<ParticleSet*>(this)->scalar_field(name);
}

template <int dim>
std::vector<std::string> ParticleSet<dim>::scalar_field_names() const {
  std::vector<std::string> names;
  for (const auto& f : scalar_fields_)
    names.push_back(f.first);
  return names;
}

template class ParticleSet<2>;
template class ParticleSet<3>;

} // namespace spinesim::meshfree
