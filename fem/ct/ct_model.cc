#include "fem/ct/ct_model.h"

#include "fem/ct/ct_value_check.h"
#include "fem/ct/ct_volume.h"
#include "fem/ct/density_calibration.h"
#include "fem/ct/density_modulus_law.h"

#include <memory>
#include <sstream>

namespace spinesim::fem {

std::string CtModel::summary() const {
  std::ostringstream out;
  out << "CT model: " << mesh.cell_density.size() << " cells from " << mesh.n_selected_voxels
      << " selected voxels, volume " << mesh.total_volume() * 1e6 << " cm^3 (voxels "
      << mesh.selected_volume * 1e6 << "), mass " << mesh.total_mass() * 1e3 << " g (voxels "
      << mesh.selected_mass * 1e3 << ")\n"
      << "  components " << mesh.n_components << ", added cells (non-manifold repair) "
      << mesh.n_added_cells << ", dropped cells " << mesh.n_dropped_cells << " ("
      << mesh.n_dropped_voxels << " voxels), floored cells " << floored_cells << ", end faces z- "
      << end_faces.lower << " / z+ " << end_faces.upper;
  return out.str();
}

CtModel build_ct_model(const CtParameters& p, dealii::Triangulation<3>& triangulation) {
  const CtVolume image = read_ct_volume(p.image_file);
  check_image_values(image);
  std::unique_ptr<LabelVolume> labels;
  if (!p.labels.empty())
    labels = std::make_unique<LabelVolume>(read_label_volume(p.label_file));
  const DensityCalibration calibration(DensityCalibration::parse_value_type(p.value_type),
                                       p.calibration_intercept, p.calibration_slope);
  VoxelMesher::Options options;
  options.labels = p.labels;
  options.density_threshold = p.density_threshold;
  options.coarsening_factor = p.coarsening_factor;
  options.block_rule =
      p.block_rule == "any" ? VoxelMesher::BlockRule::any : VoxelMesher::BlockRule::majority;
  options.keep_largest_component = p.keep_largest_component;
  const VoxelMesher mesher(image, calibration.densities(image), labels.get(), options);

  CtModel model;
  model.mesh = mesher.build(triangulation);
  const DensityModulusLaw law(p.density_modulus_law, p.constant_modulus, p.minimum_density,
                              p.minimum_modulus);
  // Cells by coarse id: material id from the triangulation (all ranks hold the coarse mesh).
  std::vector<int> material(model.mesh.cell_density.size(), 0);
  for (const auto& cell : triangulation.cell_iterators_on_level(0))
    material[cell->id().get_coarse_cell_id()] = cell->material_id();
  std::vector<double> law_density; // cells the law applies to
  std::vector<std::size_t> law_cell;
  model.cell_modulus.assign(material.size(), 0.0);
  for (std::size_t c = 0; c < material.size(); ++c) {
    if (const auto d = p.label_densities.find(material[c]); d != p.label_densities.end())
      model.mesh.cell_density[c] = d->second;
    if (const auto e = p.label_moduli.find(material[c]); e != p.label_moduli.end()) {
      model.cell_modulus[c] = e->second;
    } else {
      law_density.push_back(model.mesh.cell_density[c]);
      law_cell.push_back(c);
    }
  }
  const auto evaluation = law.evaluate(law_density);
  for (std::size_t n = 0; n < law_cell.size(); ++n)
    model.cell_modulus[law_cell[n]] = evaluation.modulus[n];
  model.floored_cells = evaluation.floored_cells;
  model.warnings = bone_density_warnings(law_density, p.image_file);
  model.cell_label = std::move(material);
  model.poisson_ratio = p.poisson_ratio;
  if (p.mark_end_faces)
    model.end_faces = p.end_face_labels.empty()
                          ? mark_end_faces<3>(triangulation, 2, 4, 5)
                          : mark_end_faces<3>(triangulation, 2, 4, 5, 0,
                                              dealii::types::material_id(p.end_face_labels[0]),
                                              dealii::types::material_id(p.end_face_labels[1]));
  return model;
}

} // namespace spinesim::fem
