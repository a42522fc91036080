#ifndef SPINESIM_FEM_CT_CT_BOX_H
#define SPINESIM_FEM_CT_CT_BOX_H

// A box of a CT image as a density map for a scenario's own block mesh (a drilled block, a
// block a screw is pulled from): the calibrated density at a point x of the block is that of
// the voxel nearest Top centre + R x. R's columns are the block's axes in the image's physical
// frame (LPS for medical images): z = Block z axis (out of the bone at the top face: a drill or
// screw entering the top face goes along −z), x the image's x (or y) made normal to it. The entries
// are declared in the current subsection ("CT" by convention); an empty Image file switches the box
// off.

#include "fem/ct/ct_volume.h"
#include "fem/ct/density_modulus_law.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::fem {

struct CtBoxParameters {
  std::string image_file;             // empty: no CT box
  std::string value_type = "density"; // density (mg/cm^3) | hu
  double intercept = 0, slope = 1e-3; // rho = a + b HU [g/cm^3] (hu)
  dealii::Point<3> top_centre;        // image point at the block's local origin [m]
  dealii::Tensor<2, 3> axes = dealii::unit_symmetric_tensor<3>(); // columns: block x, y, z
  // Top centre frame = voxel: Top centre is a (fractional) voxel index and Block z axis a
  // direction in index space, as read; CtBox maps both to the physical frame once the image's
  // geometry is known (top_centre and axes are set then).
  bool voxel_frame = false;
  std::array<double, 3> top_centre_voxel{{0, 0, 0}}, z_axis_voxel{{0, 0, 1}};
  // top_centre and the axes from a physical point [m] and the block's z direction (non-zero).
  void set_frame(const dealii::Point<3>& centre, dealii::Tensor<1, 3> z);
  std::string modulus_law = "morgan2003_vertebra";
  double minimum_density = 0.01; // [g/cm^3] floor before the law
  // Segmentation on the image's grid (declared with `labels`): voxels of bone_labels (every
  // non-zero label if empty) are bone, label 0 is background (soft tissue, air), and other
  // labels (PMMA caps, say) are neither. Empty: every voxel is bone.
  std::string label_file;
  std::vector<int> bone_labels;
  bool enabled() const { return !image_file.empty(); }

  // `what` completes the help texts: what the box replaces, e.g. "the layered block".
  // `labels`: also declare Label file and Bone labels (scenarios that use them).
  static void declare(dealii::ParameterHandler& prm, const std::string& what,
                      const std::string& default_law = "morgan2003_vertebra", bool labels = false);
  // `where` prefixes the parameter names in errors, e.g. "Bone block/CT/". The image file is
  // resolved by `resolve` (e.g. against the project) and must exist.
  void parse(const dealii::ParameterHandler& prm, const std::string& where,
             const std::function<std::string(const std::string&)>& resolve, bool labels = false);
};

class CtBox {
 public:
  // Reads and calibrates the image (InvalidInput naming the file if it cannot be read).
  explicit CtBox(const CtBoxParameters& parameters);
  // [g/cm^3] of the voxel nearest the block point x; NaN outside the image.
  double density(const dealii::Point<3>& x) const;
  // Young's modulus [Pa] of the law at x (floors applied).
  double modulus(const dealii::Point<3>& x) const { return law_.modulus(density(x)); }
  bool has_labels() const { return !labels_.empty(); }
  // The label of the voxel nearest x (0 without a label file), −1 outside the image.
  int label(const dealii::Point<3>& x) const;
  // Whether x is bone: always without a label file; otherwise its label is a bone label.
  bool is_bone(const dealii::Point<3>& x) const;
  bool is_bone_label(int label) const;
  const DensityModulusLaw& law() const { return law_; }
  // InvalidInput naming `where` + "Top centre" if a corner of the box [lower, upper] (block
  // coordinates) lies outside the image.
  void require_inside(const dealii::Point<3>& lower, const dealii::Point<3>& upper,
                      const std::string& where) const;
  const CtBoxParameters& parameters() const { return prm_; }
  // "top centre (x, y, z) mm, z axis (a, b, c)" in the image's physical frame, preceded by the
  // voxel index and index-space axis when they were given that way; for the log.
  std::string frame_description() const;

 private:
  // The voxel nearest x, false outside the image.
  bool voxel_of(const dealii::Point<3>& x, std::size_t& index) const;
  CtBoxParameters prm_;
  VolumeGeometry geometry_;
  std::vector<double> density_; // [g/cm^3] per voxel
  std::vector<int> labels_;     // per voxel, empty without a label file
  DensityModulusLaw law_;
};

} // namespace spinesim::fem

#endif
