#include "meshfree/particle_output.h"

#include <deal.II/base/data_out_base.h>

#include <algorithm>
#include <fstream>
#include <tuple>

namespace spinesim::meshfree {

namespace {

template <int dim>
class ParticleDataOut : public dealii::DataOutInterface<0, dim> {
 public:
  ParticleDataOut(const ParticleSet<dim>& p, unsigned int count) {
    names_.clear();
    for (const char* vec : {"displacement", "velocity"})
      for (unsigned int d = 0; d < dim; ++d)
        names_.push_back(vec);
    for (const char* s : {"damage", "volume", "material_id", "temperature"})
      names_.push_back(s);
    const auto fields = p.scalar_field_names();
    for (const auto& f : fields)
      names_.push_back(f);

    patches_.resize(std::min(count, p.size()));
    for (unsigned int i = 0; i < patches_.size(); ++i) {
      auto& patch = patches_[i];
      patch.vertices[0] = p.current_position(i);
      patch.patch_index = i;
      patch.data.reinit(names_.size(), 1);
      unsigned int c = 0;
      for (unsigned int d = 0; d < dim; ++d)
        patch.data(c++, 0) = p.displacement(i)[d];
      for (unsigned int d = 0; d < dim; ++d)
        patch.data(c++, 0) = p.velocity(i)[d];
      patch.data(c++, 0) = p.damage(i);
      patch.data(c++, 0) = p.volume(i);
      patch.data(c++, 0) = p.material_id(i);
      patch.data(c++, 0) = p.temperature(i);
      for (const auto& f : fields)
        patch.data(c++, 0) = p.scalar_field(f)[i];
    }
  }

 private:
  const std::vector<dealii::DataOutBase::Patch<0, dim>>& get_patches() const override {
    return patches_;
  }
  std::vector<std::string> get_dataset_names() const override { return names_; }
  std::vector<std::tuple<unsigned int, unsigned int, std::string,
                         dealii::DataComponentInterpretation::DataComponentInterpretation>>
  get_nonscalar_data_ranges() const override {
    using dealii::DataComponentInterpretation::component_is_part_of_vector;
    return {std::make_tuple(0u, dim - 1u, std::string("displacement"), component_is_part_of_vector),
            std::make_tuple(dim + 0u, 2u * dim - 1u, std::string("velocity"),
                            component_is_part_of_vector)};
  }

  std::vector<std::string> names_;
  std::vector<dealii::DataOutBase::Patch<0, dim>> patches_;
};

} // namespace

template <int dim>
void write_particles_vtu(const ParticleSet<dim>& particles, const std::string& file_name,
                         unsigned int count) {
  ParticleDataOut<dim> out(particles, count);
  std::ofstream file(file_name);
  dealii::DataOutBase::VtkFlags flags;
  flags.compression_level = dealii::DataOutBase::VtkFlags::best_speed; // see mechanics output
  out.set_flags(flags);
  out.write_vtu(file);
}

template <int dim>
void write_particles_pvtu(const ParticleSet<dim>& particles, const std::string& file_name,
                          const std::vector<std::string>& pieces) {
  ParticleDataOut<dim> out(particles, 0); // the field names only
  std::ofstream file(file_name);
  out.write_pvtu_record(file, pieces);
}

template void write_particles_vtu(const ParticleSet<2>&, const std::string&, unsigned int);
template void write_particles_vtu(const ParticleSet<3>&, const std::string&, unsigned int);
template void write_particles_pvtu(const ParticleSet<2>&, const std::string&,
                                   const std::vector<std::string>&);
template void write_particles_pvtu(const ParticleSet<3>&, const std::string&,
                                   const std::vector<std::string>&);

} // namespace spinesim::meshfree
