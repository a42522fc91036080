#include "fem/ct/ct_box.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/ct/density_calibration.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace spinesim::fem {

void CtBoxParameters::declare(dealii::ParameterHandler& prm, const std::string& what,
                              const std::string& default_law) {
  using namespace dealii::Patterns;
  prm.declare_entry("Image file", "", Anything(),
                    "A CT image whose box replaces " + what +
                        " (empty: no CT); relative to the project or absolute [-]. Each cell "
                        "takes the calibrated density of the voxel nearest its centre.");
  DensityCalibration::declare(prm);
  prm.declare_entry("Top centre", "", Anything(),
                    "The image point at the centre of the block's top face, where x = y = z = 0 "
                    "of the block, in the image's physical frame (LPS for medical images) [mm].");
  prm.declare_entry("Block z axis", "0,0,1", Anything(),
                    "The block's z axis in the image's frame, pointing out of the bone through "
                    "the top face (a tool entering the top face moves along minus this); the "
                    "block's x axis is the image's x (its y if z is along x) made normal to it "
                    "[-].");
  prm.declare_entry("Density modulus law", default_law, Selection(DensityModulusLaw::names()),
                    "E(rho) of each cell (fem/ct/density_modulus_law.h) [-].");
  prm.declare_entry("Minimum density", "0.01", Double(0),
                    "Floor of the density before the law (voxels of marrow or air) [g/cm^3].");
}

void CtBoxParameters::parse(const dealii::ParameterHandler& prm, const std::string& where,
                            const std::function<std::string(const std::string&)>& resolve) {
  image_file = prm.get("Image file");
  value_type = prm.get("Value type");
  intercept = prm.get_double("Calibration intercept");
  slope = prm.get_double("Calibration slope");
  modulus_law = prm.get("Density modulus law");
  minimum_density = prm.get_double("Minimum density");
  if (!enabled())
    return;
  image_file = resolve(image_file);
  const auto c = parse_numbers(prm.get("Top centre"), where + "Top centre", 3, "[mm]");
  top_centre = dealii::Point<3>(1e-3 * c[0], 1e-3 * c[1], 1e-3 * c[2]);
  const auto z = parse_numbers(prm.get("Block z axis"), where + "Block z axis", 3);
  dealii::Tensor<1, 3> ez({z[0], z[1], z[2]});
  if (!(ez.norm() > 0))
    throw InvalidInput(where + "Block z axis", prm.get("Block z axis"), "a non-zero direction");
  ez /= ez.norm();
  dealii::Tensor<1, 3> ex({1, 0, 0});
  if (std::abs(ex * ez) > 0.9)
    ex = dealii::Tensor<1, 3>({0, 1, 0});
  ex -= (ex * ez) * ez;
  ex /= ex.norm();
  const dealii::Tensor<1, 3> ey = dealii::cross_product_3d(ez, ex);
  for (unsigned int r = 0; r < 3; ++r) {
    axes[r][0] = ex[r];
    axes[r][1] = ey[r];
    axes[r][2] = ez[r];
  }
  if (!std::filesystem::exists(image_file))
    throw InvalidInput(where + "Image file", image_file,
                       "an existing image file (" + accepted_image_formats() +
                           "), relative to the project or absolute");
  if (!(minimum_density > 0))
    throw InvalidInput(where + "Minimum density", std::to_string(minimum_density),
                       "a positive density [g/cm^3]");
}

CtBox::CtBox(const CtBoxParameters& parameters)
    : prm_(parameters), law_(parameters.modulus_law, 1e9, parameters.minimum_density, 1e6) {
  const CtVolume image = read_ct_volume(prm_.image_file);
  geometry_ = image;
  density_ = DensityCalibration(DensityCalibration::parse_value_type(prm_.value_type),
                                prm_.intercept, prm_.slope)
                 .densities(image);
}

double CtBox::density(const dealii::Point<3>& x) const {
  const auto idx = geometry_.index_of(prm_.top_centre + prm_.axes * x);
  unsigned int ijk[3];
  for (unsigned int d = 0; d < 3; ++d) {
    const double i = std::round(idx[d]);
    if (!(i >= 0 && i < geometry_.size[d]))
      return std::numeric_limits<double>::quiet_NaN();
    ijk[d] = static_cast<unsigned int>(i);
  }
  return density_[geometry_.linear_index(ijk[0], ijk[1], ijk[2])];
}

void CtBox::require_inside(const dealii::Point<3>& lower, const dealii::Point<3>& upper,
                           const std::string& where) const {
  for (unsigned int corner = 0; corner < 8; ++corner) {
    const dealii::Point<3> x((corner & 1) ? upper[0] : lower[0], (corner & 2) ? upper[1] : lower[1],
                             (corner & 4) ? upper[2] : lower[2]);
    if (!std::isfinite(density(x))) {
      std::ostringstream s;
      s << "the block's corner (" << x[0] * 1e3 << ", " << x[1] * 1e3 << ", " << x[2] * 1e3
        << ") mm lies outside " << prm_.image_file;
      throw InvalidInput(where + "Top centre", s.str(),
                         "a top centre that keeps the block inside the image");
    }
  }
}

} // namespace spinesim::fem
