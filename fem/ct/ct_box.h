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
  std::string modulus_law = "morgan2003_vertebra";
  double minimum_density = 0.01; // [g/cm^3] floor before the law
  bool enabled() const { return !image_file.empty(); }

  // `what` completes the help texts: what the box replaces, e.g. "the layered block".
  static void declare(dealii::ParameterHandler& prm, const std::string& what,
                      const std::string& default_law = "morgan2003_vertebra");
  // `where` prefixes the parameter names in errors, e.g. "Bone block/CT/". The image file is
  // resolved by `resolve` (e.g. against the project) and must exist.
  void parse(const dealii::ParameterHandler& prm, const std::string& where,
             const std::function<std::string(const std::string&)>& resolve);
};

class CtBox {
 public:
  // Reads and calibrates the image (InvalidInput naming the file if it cannot be read).
  explicit CtBox(const CtBoxParameters& parameters);
  // [g/cm^3] of the voxel nearest the block point x; NaN outside the image.
  double density(const dealii::Point<3>& x) const;
  // Young's modulus [Pa] of the law at x (floors applied).
  double modulus(const dealii::Point<3>& x) const { return law_.modulus(density(x)); }
  const DensityModulusLaw& law() const { return law_; }
  // InvalidInput naming `where` + "Top centre" if a corner of the box [lower, upper] (block
  // coordinates) lies outside the image.
  void require_inside(const dealii::Point<3>& lower, const dealii::Point<3>& upper,
                      const std::string& where) const;
  const CtBoxParameters& parameters() const { return prm_; }

 private:
  CtBoxParameters prm_;
  VolumeGeometry geometry_;
  std::vector<double> density_; // [g/cm^3] per voxel
  DensityModulusLaw law_;
};

} // namespace spinesim::fem

#endif
