#ifndef SPINESIM_FEM_CT_CT_VALUE_CHECK_H
#define SPINESIM_FEM_CT_CT_VALUE_CHECK_H

// Image values that no calibration turns into bone. A file can be complete (the byte counts
// of image_file_check.h agree) and still hold nothing usable: a blank (zero-filled) volume, or
// non-finite floats. Those are bad input. Calibrated densities that bone cannot have are
// warnings: the run is possible, its stiffness is not to be trusted.

#include "fem/ct/ct_volume.h"

#include <string>
#include <vector>

namespace spinesim::fem {

// Apparent density of compact cortical bone is about 1.8–2.0 g/cm^3 (Carter & Hayes 1977,
// J Bone Joint Surg Am 59:954); a bone cell above this is metal, a beam-hardening streak or a
// calibration off by a factor [g/cm^3].
constexpr double densest_plausible_bone = 2.2;

// InvalidInput naming the image file and what `Image file` must hold: a non-finite voxel
// (NaN or inf, with its index), or a volume whose voxels all carry the same value.
void check_image_values(const CtVolume& image);

// Warnings (one sentence each, empty when none) on the calibrated densities [g/cm^3] of the
// cells whose modulus comes from the density-modulus law: cells denser than compact bone, a
// majority below zero, or no contrast at all among them.
std::vector<std::string> bone_density_warnings(const std::vector<double>& cell_density,
                                               const std::string& image_file);

} // namespace spinesim::fem

#endif
