#ifndef SPINESIM_FEM_CT_CT_VOLUME_H
#define SPINESIM_FEM_CT_CT_VOLUME_H

// A 3-D image volume in plain arrays, read through ITK (NIfTI .nii/.nii.gz, NRRD .nrrd/.nhdr,
// MetaImage .mha/.mhd). ITK stays behind the .cc so users of this header do not compile it.
//
// Units and frame: ITK reports spacing and origin in millimetres for every format (NIfTI files
// store their spatial unit and ITK scales them to mm; NRRD and MetaImage have no unit and are
// taken as mm by convention). They are converted here to metres. Physical points are in ITK's
// patient frame (LPS for medical images), so orientation, spacing and origin survive exactly:
//   x(i,j,k) = origin + direction * diag(spacing) * (i,j,k)^T,
// with x(i,j,k) the centre of voxel (i,j,k). Voxel values are stored with i fastest:
//   linear index = i + nx * (j + ny * k).

#include <deal.II/base/point.h>

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace spinesim::fem {

// Grid geometry shared by value and label volumes.
struct VolumeGeometry {
  std::array<unsigned int, 3> size{{0, 0, 0}};   // voxels per image axis (nx, ny, nz)
  std::array<double, 3> spacing{{1, 1, 1}};      // [m] voxel edge lengths along the image axes
  std::array<double, 3> origin{{0, 0, 0}};       // [m] centre of voxel (0,0,0)
  std::array<std::array<double, 3>, 3> direction{// direction[r][c]: component r of axis c
                                                 {{{1, 0, 0}}, {{0, 1, 0}}, {{0, 0, 1}}}};

  std::size_t n_voxels() const { return std::size_t(size[0]) * size[1] * size[2]; }
  std::size_t linear_index(unsigned int i, unsigned int j, unsigned int k) const {
    return i + std::size_t(size[0]) * (j + std::size_t(size[1]) * k);
  }
  double voxel_volume() const { return spacing[0] * spacing[1] * spacing[2]; } // [m^3]
  // Physical point [m] of a (possibly fractional) index; (i,j,k) integer = voxel centre.
  dealii::Point<3> point(double i, double j, double k) const;
  // The (fractional) index of a physical point [m], the inverse of point(): integer values at
  // voxel centres, outside [-0.5, size - 0.5] outside the image.
  std::array<double, 3> index_of(const dealii::Point<3>& x) const;
  // +1 for a right-handed image frame, -1 when the direction matrix flips an axis.
  double handedness() const;
  // Same size, spacing, origin and direction up to `relative_tolerance` of the spacing.
  bool same_grid(const VolumeGeometry& other, double relative_tolerance = 1e-6) const;
};

// Scalar voxel values (grey values, HU or density as stored in the file).
struct CtVolume : VolumeGeometry {
  std::string file_name;
  std::vector<double> values;

  double value(unsigned int i, unsigned int j, unsigned int k) const {
    return values[linear_index(i, j, k)];
  }
};

// Integer labels (segmentation), same layout as CtVolume.
struct LabelVolume : VolumeGeometry {
  std::string file_name;
  std::vector<int> labels;

  int label(unsigned int i, unsigned int j, unsigned int k) const {
    return labels[linear_index(i, j, k)];
  }
  // Number of voxels carrying `label`.
  std::size_t count(int label) const;
};

// File extensions the readers accept, for messages.
std::string accepted_image_formats();

// Reads a 3-D scalar volume, any pixel type converted to double (NIfTI scl_slope/scl_inter
// applied by ITK); a directory is read as a DICOM series (Rescale Slope/Intercept applied).
// InvalidInput naming the file for a missing, unreadable, non-scalar or non-3-D image.
CtVolume read_ct_volume(const std::string& file_name);

// Reads a 3-D label volume. Non-integral values (a label map stored as float that was
// resampled) are rejected with InvalidInput naming the file and the first bad voxel.
LabelVolume read_label_volume(const std::string& file_name);

// Writes a volume (double pixels; labels as 16-bit signed integers) in the format given by the
// extension, spacing and origin converted back to mm. For tests, and for exporting calibrated
// density maps.
void write_ct_volume(const CtVolume& volume, const std::string& file_name);
void write_label_volume(const LabelVolume& volume, const std::string& file_name);
// Writes a CT volume as a DICOM series into `directory` (one file per slice along the image's
// third axis, 16-bit values rounded, Rescale Slope 1 and Intercept 0), readable back through
// read_ct_volume(directory). For tests, and for viewers that take DICOM only.
// `series_uid`: the Series Instance UID (0020,000E) of the slices.
void write_dicom_series(const CtVolume& volume, const std::string& directory,
                        const std::string& series_uid = "1.2.826.0.1.3680043.2.1125.1.1");

} // namespace spinesim::fem

#endif
