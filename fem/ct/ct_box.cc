#include "fem/ct/ct_box.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/ct/density_calibration.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace spinesim::fem {

void CtBoxParameters::declare(dealii::ParameterHandler& prm, const std::string& what,
                              const std::string& default_law, bool labels) {
  using namespace dealii::Patterns;
  prm.declare_entry("Image file", "", FileName(FileName::input),
                    "A CT image (NIfTI, NRRD, MetaImage, or a directory of one DICOM series) "
                    "whose box replaces " +
                        what +
                        " (empty: no CT); relative to the project or absolute [-]. Each cell "
                        "takes the calibrated density of the voxel nearest its centre.");
  DensityCalibration::declare(prm);
  prm.declare_entry("Top centre", "", Anything(),
                    "The image point at the centre of the block's top face, where x = y = z = 0 "
                    "of the block: in the image's physical frame (LPS for medical images) [mm], "
                    "or with Top centre frame = voxel as image indices i, j, k [-].");
  prm.declare_entry("Block z axis", "0,0,1", Anything(),
                    "The block's z axis, pointing out of the bone through the top face (a tool "
                    "entering the top face moves along minus this): a direction in the image's "
                    "physical frame, or in index space with Top centre frame = voxel. The "
                    "block's x axis is the physical x (its y if z is along x) made normal to "
                    "it, in either frame [-].");
  prm.declare_entry("Top centre frame", "physical", Selection("physical|voxel"),
                    "Frame of Top centre and Block z axis [-]. physical: the image's physical "
                    "frame in mm (LPS for medical images). voxel: image indices i, j, k as a "
                    "viewer shows them (0-based, fractions allowed), and the axis a direction "
                    "in index space, which the voxel spacing and the image's direction matrix "
                    "map to the physical frame; the log gives both.");
  prm.declare_entry("Density modulus law", default_law, Selection(DensityModulusLaw::names()),
                    "E(rho) of each cell (fem/ct/density_modulus_law.h) [-].");
  prm.declare_entry("Minimum density", "0.01", Double(0),
                    "Floor of the density before the law (voxels of marrow or air) [g/cm^3].");
  if (!labels)
    return;
  prm.declare_entry("Label file", "", FileName(FileName::input),
                    "Segmentation of the image on its grid (integer labels; relative to the "
                    "project or absolute), e.g. the _seg file of verse004; empty: every voxel "
                    "is bone [-]. Voxels of Bone labels are bone, label 0 is background (soft "
                    "tissue, air), any other label (PMMA caps) is neither.");
  prm.declare_entry("Bone labels", "", List(Integer(1), 0, 255),
                    "Labels that are bone, comma list (empty: every non-zero label) [-].");
}

void CtBoxParameters::parse(const dealii::ParameterHandler& prm, const std::string& where,
                            const std::function<std::string(const std::string&)>& resolve,
                            bool labels) {
  image_file = prm.get("Image file");
  value_type = prm.get("Value type");
  intercept = prm.get_double("Calibration intercept");
  slope = prm.get_double("Calibration slope");
  modulus_law = prm.get("Density modulus law");
  minimum_density = prm.get_double("Minimum density");
  label_file.clear();
  bone_labels.clear();
  if (labels) {
    label_file = prm.get("Label file");
    for (const auto& l : dealii::Utilities::split_string_list(prm.get("Bone labels"), ','))
      bone_labels.push_back(dealii::Utilities::string_to_int(l));
    if (label_file.empty() && !bone_labels.empty())
      throw InvalidInput(where + "Bone labels", prm.get("Bone labels"),
                         "empty without a Label file (there are no labels to choose from)");
  }
  if (!enabled()) {
    if (!label_file.empty())
      throw InvalidInput(where + "Label file", label_file, "empty without an Image file");
    return;
  }
  image_file = resolve(image_file);
  if (!label_file.empty()) {
    label_file = resolve(label_file);
    if (!std::filesystem::exists(label_file))
      throw InvalidInput(where + "Label file", label_file,
                         "an existing label image on the grid of the Image file, relative to the "
                         "project or absolute");
  }
  voxel_frame = prm.get("Top centre frame") == "voxel";
  const auto c = parse_numbers(prm.get("Top centre"), where + "Top centre", 3,
                               voxel_frame ? "[voxel indices i, j, k]" : "[mm]");
  const auto z = parse_numbers(prm.get("Block z axis"), where + "Block z axis", 3);
  const dealii::Tensor<1, 3> ez({z[0], z[1], z[2]});
  if (!(ez.norm() > 0) || !std::isfinite(ez.norm()))
    throw InvalidInput(where + "Block z axis", prm.get("Block z axis"), "a non-zero direction");
  if (voxel_frame) { // mapped by CtBox once the image's grid is read
    top_centre_voxel = {{c[0], c[1], c[2]}};
    z_axis_voxel = {{z[0], z[1], z[2]}};
  } else {
    set_frame(dealii::Point<3>(1e-3 * c[0], 1e-3 * c[1], 1e-3 * c[2]), ez);
  }
  if (!std::filesystem::exists(image_file))
    throw InvalidInput(where + "Image file", image_file,
                       "an existing image file (" + accepted_image_formats() +
                           "), relative to the project or absolute");
  if (!(minimum_density > 0))
    throw InvalidInput(where + "Minimum density", std::to_string(minimum_density),
                       "a positive density [g/cm^3]");
}

void CtBoxParameters::set_frame(const dealii::Point<3>& centre, dealii::Tensor<1, 3> ez) {
  // A voxel-frame axis is checked again once mapped (a tiny index direction can underflow).
  if (!(ez.norm() > 0) || !std::isfinite(ez.norm()))
    throw InvalidInput("CT/Block z axis", "a direction of length " + std::to_string(ez.norm()),
                       "a non-zero direction");
  top_centre = centre;
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
}

CtBox::CtBox(const CtBoxParameters& parameters)
    : prm_(parameters), law_(parameters.modulus_law, 1e9, parameters.minimum_density, 1e6) {
  const CtVolume image = read_ct_volume(prm_.image_file);
  geometry_ = image;
  if (prm_.voxel_frame) {
    // x = origin + D diag(spacing) i (ct_volume.h); a direction maps by D diag(spacing) alone.
    dealii::Point<3> centre;
    dealii::Tensor<1, 3> z;
    for (unsigned int r = 0; r < 3; ++r) {
      centre[r] = image.origin[r];
      for (unsigned int c = 0; c < 3; ++c) {
        centre[r] += image.direction[r][c] * image.spacing[c] * prm_.top_centre_voxel[c];
        z[r] += image.direction[r][c] * image.spacing[c] * prm_.z_axis_voxel[c];
      }
    }
    prm_.set_frame(centre, z);
  }
  density_ = DensityCalibration(DensityCalibration::parse_value_type(prm_.value_type),
                                prm_.intercept, prm_.slope)
                 .densities(image);
  if (!prm_.label_file.empty()) {
    const LabelVolume labels = read_label_volume(prm_.label_file);
    // 1e-3 of a voxel: nearest-voxel lookups need no more, and a float32 NIfTI header beside
    // a DICOM series' decimal positions differs by about 1e-5 mm at 500 mm.
    if (!labels.same_grid(image, 1e-3)) {
      std::ostringstream have, want;
      auto describe = [](std::ostringstream& o, const VolumeGeometry& g) {
        o << g.size[0] << " x " << g.size[1] << " x " << g.size[2] << " voxels of "
          << g.spacing[0] * 1e3 << " x " << g.spacing[1] * 1e3 << " x " << g.spacing[2] * 1e3
          << " mm from (" << g.origin[0] * 1e3 << ", " << g.origin[1] * 1e3 << ", "
          << g.origin[2] * 1e3 << ") mm";
      };
      describe(have, labels);
      describe(want, image);
      throw InvalidInput(prm_.label_file,
                         "a label image on another grid: " + have.str() +
                             " (or other axis directions)",
                         "the grid of " + prm_.image_file + ": " + want.str());
    }
    labels_ = labels.labels;
  }
}

std::string CtBox::frame_description() const {
  std::ostringstream o;
  o.precision(6);
  if (prm_.voxel_frame)
    o << "voxel (" << prm_.top_centre_voxel[0] << ", " << prm_.top_centre_voxel[1] << ", "
      << prm_.top_centre_voxel[2] << ") along index direction (" << prm_.z_axis_voxel[0] << ", "
      << prm_.z_axis_voxel[1] << ", " << prm_.z_axis_voxel[2] << "): ";
  o << "top centre (" << 1e3 * prm_.top_centre[0] << ", " << 1e3 * prm_.top_centre[1] << ", "
    << 1e3 * prm_.top_centre[2] << ") mm, block z axis (" << prm_.axes[0][2] << ", "
    << prm_.axes[1][2] << ", " << prm_.axes[2][2] << ") in the image's physical frame";
  return o.str();
}

bool CtBox::voxel_of(const dealii::Point<3>& x, std::size_t& index) const {
  const auto idx = geometry_.index_of(prm_.top_centre + prm_.axes * x);
  unsigned int ijk[3];
  for (unsigned int d = 0; d < 3; ++d) {
    const double i = std::round(idx[d]);
    if (!(i >= 0 && i < geometry_.size[d]))
      return false;
    ijk[d] = static_cast<unsigned int>(i);
  }
  index = geometry_.linear_index(ijk[0], ijk[1], ijk[2]);
  return true;
}

double CtBox::density(const dealii::Point<3>& x) const {
  std::size_t i;
  return voxel_of(x, i) ? density_[i] : std::numeric_limits<double>::quiet_NaN();
}

int CtBox::label(const dealii::Point<3>& x) const {
  std::size_t i;
  if (!voxel_of(x, i))
    return -1;
  return labels_.empty() ? 0 : labels_[i];
}

bool CtBox::is_bone_label(int l) const {
  if (labels_.empty())
    return true;
  if (prm_.bone_labels.empty())
    return l > 0;
  return std::find(prm_.bone_labels.begin(), prm_.bone_labels.end(), l) != prm_.bone_labels.end();
}

bool CtBox::is_bone(const dealii::Point<3>& x) const {
  return labels_.empty() || is_bone_label(label(x));
}

void CtBox::require_inside(const dealii::Point<3>& lower, const dealii::Point<3>& upper,
                           const std::string& where) const {
  for (unsigned int corner = 0; corner < 8; ++corner) {
    const dealii::Point<3> x((corner & 1) ? upper[0] : lower[0], (corner & 2) ? upper[1] : lower[1],
                             (corner & 4) ? upper[2] : lower[2]);
    if (!std::isfinite(density(x))) {
      std::ostringstream s;
      const auto idx = geometry_.index_of(prm_.top_centre + prm_.axes * x);
      s << "the block's corner (" << x[0] * 1e3 << ", " << x[1] * 1e3 << ", " << x[2] * 1e3
        << ") mm (block frame; voxel (" << idx[0] << ", " << idx[1] << ", " << idx[2]
        << ")) lies outside " << prm_.image_file << " (" << geometry_.size[0] << " x "
        << geometry_.size[1] << " x " << geometry_.size[2] << " voxels); " << frame_description();
      throw InvalidInput(where + "Top centre", s.str(),
                         "a top centre that keeps the block inside the image");
    }
  }
}

} // namespace spinesim::fem
