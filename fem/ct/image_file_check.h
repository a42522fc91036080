#ifndef SPINESIM_FEM_CT_IMAGE_FILE_CHECK_H
#define SPINESIM_FEM_CT_IMAGE_FILE_CHECK_H

// Whether an image file holds all the voxel data its header announces. ITK's readers take a
// short file as a smaller or zero-filled volume without a word; this check reads the
// format's own header (NIfTI-1/2 vox_offset, MetaImage ElementDataFile and CompressedData,
// NRRD encoding and data file), inflates compressed data to its end (zlib: a truncated
// stream is an error there) and compares the byte counts.

#include <cstddef>
#include <string>
#include <vector>

namespace spinesim::fem {

// InvalidInput naming the file (and the byte counts) when the data is short or the
// compressed stream is cut. `expected_bytes`: voxels × bytes per voxel from the header.
void check_image_data_complete(const std::string& file, std::size_t expected_bytes);
// The same for the file's bytes already in memory (`file` names it and gives the format by
// its extension; detached data files are still read from beside it).
void check_image_bytes(const std::string& file, const std::vector<char>& bytes,
                       std::size_t expected_bytes);

} // namespace spinesim::fem

#endif
