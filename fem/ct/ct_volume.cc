#include "fem/ct/ct_volume.h"

#include "base/exceptions.h"
#include "fem/ct/image_file_check.h"

#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageFileWriter.h>
#include <itkImageSeriesReader.h>
#include <itkImageSeriesWriter.h>
#include <itkMetaDataObject.h>
#include <itkMetaImageIO.h>
#include <itkNiftiImageIO.h>
#include <itkNrrdImageIO.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <sstream>

namespace spinesim::fem {

namespace {

constexpr double metres_per_mm = 1e-3;

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The ImageIO for a file name, chosen by extension: explicit objects rather than ITK's factory
// registry, which needs generated registration code and would accept formats we do not test.
itk::ImageIOBase::Pointer image_io_for(const std::string& file_name) {
  std::string lower = file_name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ends_with(lower, ".nii") || ends_with(lower, ".nii.gz"))
    return itk::NiftiImageIO::New().GetPointer();
  if (ends_with(lower, ".nrrd") || ends_with(lower, ".nhdr"))
    return itk::NrrdImageIO::New().GetPointer();
  if (ends_with(lower, ".mha") || ends_with(lower, ".mhd"))
    return itk::MetaImageIO::New().GetPointer();
  throw InvalidInput(file_name, "unknown image file extension", accepted_image_formats());
}

using DoubleImage = itk::Image<double, 3>;

// The image's grid in metres; InvalidInput for an empty image or a non-positive spacing.
void take_geometry(const DoubleImage& image, const std::string& file_name,
                   VolumeGeometry& geometry) {
  const auto region = image.GetLargestPossibleRegion();
  for (unsigned int d = 0; d < 3; ++d) {
    geometry.size[d] = static_cast<unsigned int>(region.GetSize()[d]);
    geometry.spacing[d] = image.GetSpacing()[d] * metres_per_mm;
    geometry.origin[d] = image.GetOrigin()[d] * metres_per_mm;
    for (unsigned int c = 0; c < 3; ++c)
      geometry.direction[d][c] = image.GetDirection()(d, c);
  }
  if (geometry.n_voxels() == 0)
    throw InvalidInput(file_name, "image has no voxels", "a non-empty 3-D scalar volume");
  for (unsigned int d = 0; d < 3; ++d)
    if (!(geometry.spacing[d] > 0) || !std::isfinite(geometry.spacing[d]))
      throw InvalidInput(file_name, "non-positive voxel spacing along axis " + std::to_string(d),
                         "positive spacings");
}

// A directory holding one DICOM series (GDCM through ITK: slices sorted by their position
// along the slice normal, Rescale Slope/Intercept applied, so CT values arrive in HU). More
// than one series, a single slice, or slices not evenly spaced (a missing slice would
// otherwise stretch the volume) are bad input naming the directory.
DoubleImage::Pointer read_dicom_series(const std::string& directory, VolumeGeometry& geometry) {
  auto names = itk::GDCMSeriesFileNames::New();
  std::vector<std::string> uids, files;
  try {
    names->SetUseSeriesDetails(true);
    names->SetDirectory(directory);
    uids = names->GetSeriesUIDs();
    if (uids.size() == 1)
      files = names->GetFileNames(uids.front());
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(directory, std::string("cannot scan for DICOM files: ") + e.GetDescription(),
                       accepted_image_formats());
  }
  if (uids.empty())
    throw InvalidInput(directory, "no DICOM series in this directory", accepted_image_formats());
  if (uids.size() > 1) {
    std::string list;
    for (const auto& u : uids)
      list += (list.empty() ? "" : ", ") + u;
    throw InvalidInput(
        directory, std::to_string(uids.size()) + " DICOM series in one directory (" + list + ")",
        "a directory holding one series: move the others out");
  }
  if (files.size() < 2)
    throw InvalidInput(directory, "the DICOM series has " + std::to_string(files.size()) + " slice",
                       "a 3-D series of at least two slices");
  auto io = itk::GDCMImageIO::New();
  auto reader = itk::ImageSeriesReader<DoubleImage>::New();
  reader->SetImageIO(io);
  reader->SetFileNames(files);
  try {
    reader->Update();
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(directory,
                       std::string("cannot read the DICOM series: ") + e.GetDescription(),
                       "complete DICOM files of one series");
  }
  DoubleImage::Pointer image = reader->GetOutput();
  take_geometry(*image, directory, geometry);
  // Even slices: slice n's Image Position (0020,0032) must be the first's plus n h along the
  // slice normal (ITK's third axis, h its spacing from the first and last slices). Positions are
  // decimal strings a scanner rounds: 1 % of h or 0.01 mm, whichever is larger, is allowed.
  const auto& dictionaries = *reader->GetMetaDataDictionaryArray();
  const double h = geometry.spacing[2];
  const double tolerance = std::max(0.01 * h, 1e-5);
  dealii::Point<3> first;
  for (std::size_t n = 0; n < dictionaries.size(); ++n) {
    std::string position;
    if (!itk::ExposeMetaData<std::string>(*dictionaries[n], "0020|0032", position))
      throw InvalidInput(files[n], "no Image Position (Patient) (0020,0032)",
                         "CT slices with their positions");
    std::replace(position.begin(), position.end(), '\\', ' ');
    std::istringstream in(position);
    double x[3];
    if (!(in >> x[0] >> x[1] >> x[2]))
      throw InvalidInput(files[n], "Image Position (Patient) '" + position + "' unreadable",
                         "three numbers");
    const dealii::Point<3> p(x[0] * metres_per_mm, x[1] * metres_per_mm, x[2] * metres_per_mm);
    if (n == 0) {
      first = p;
      continue;
    }
    dealii::Tensor<1, 3> offset = p - first, normal;
    for (unsigned int r = 0; r < 3; ++r)
      normal[r] = geometry.direction[r][2];
    const double along = offset * normal;
    const double across = (offset - along * normal).norm();
    if (across > tolerance)
      throw InvalidInput(directory,
                         "slice " + std::to_string(n) + " (" + files[n] + ") lies " +
                             std::to_string(across * 1e3) +
                             " mm off the slice normal through the first: a tilted-gantry or "
                             "sheared series",
                         "slices stacked along their normal (resample a tilted series first)");
    if (std::abs(along - n * h) > tolerance)
      throw InvalidInput(directory,
                         "slice " + std::to_string(n) + " (" + files[n] + ") lies " +
                             std::to_string(along * 1e3) + " mm from the first, not " +
                             std::to_string(n * h * 1e3) +
                             " mm: slices are missing or unevenly spaced",
                         "a complete series of evenly spaced slices");
  }
  return image;
}

// Reads any scalar 3-D image as double, with its geometry converted to metres.
template <class Volume>
DoubleImage::Pointer read_double_image(const std::string& file_name, Volume& geometry) {
  if (std::filesystem::is_directory(file_name)) {
    auto image = read_dicom_series(file_name, geometry);
    geometry.file_name = file_name;
    return image;
  }
  if (!std::filesystem::is_regular_file(file_name))
    throw InvalidInput(file_name, "image file not found", accepted_image_formats());
  auto io = image_io_for(file_name);
  try {
    io->SetFileName(file_name);
    if (!io->CanReadFile(file_name.c_str()))
      throw InvalidInput(file_name,
                         "ITK cannot read this file as " + std::string(io->GetNameOfClass()),
                         accepted_image_formats());
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(file_name, std::string("unreadable image header: ") + e.GetDescription(),
                       accepted_image_formats());
  }
  if (io->GetNumberOfDimensions() != 3)
    throw InvalidInput(file_name,
                       "image has " + std::to_string(io->GetNumberOfDimensions()) + " dimensions",
                       "a 3-D scalar volume");
  if (io->GetNumberOfComponents() != 1)
    throw InvalidInput(file_name,
                       "image has " + std::to_string(io->GetNumberOfComponents()) +
                           " components per voxel",
                       "a 3-D scalar volume (one value per voxel)");
  // ITK takes a short file as a smaller or zero-filled volume: count the bytes first.
  check_image_data_complete(file_name, io->GetImageSizeInBytes());

  auto reader = itk::ImageFileReader<DoubleImage>::New();
  reader->SetImageIO(io);
  reader->SetFileName(file_name);
  try {
    reader->Update();
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(file_name, std::string("cannot read voxel data: ") + e.GetDescription(),
                       accepted_image_formats());
  }
  DoubleImage::Pointer image = reader->GetOutput();
  take_geometry(*image, file_name, geometry);
  geometry.file_name = file_name;
  return image;
}

// An ITK image on the grid g (mm, as ITK's readers and writers keep it), allocated.
template <class Pixel>
typename itk::Image<Pixel, 3>::Pointer allocate_image(const VolumeGeometry& g) {
  using Image = itk::Image<Pixel, 3>;
  auto image = Image::New();
  typename Image::RegionType region;
  typename Image::SizeType size;
  typename Image::SpacingType spacing;
  typename Image::PointType origin;
  typename Image::DirectionType direction;
  for (unsigned int d = 0; d < 3; ++d) {
    size[d] = g.size[d];
    spacing[d] = g.spacing[d] / metres_per_mm;
    origin[d] = g.origin[d] / metres_per_mm;
    for (unsigned int c = 0; c < 3; ++c)
      direction(d, c) = g.direction[d][c];
  }
  region.SetSize(size);
  image->SetRegions(region);
  image->SetSpacing(spacing);
  image->SetOrigin(origin);
  image->SetDirection(direction);
  image->Allocate();
  return image;
}

template <class Pixel>
void write_image(const VolumeGeometry& g, const std::vector<Pixel>& data,
                 const std::string& file_name) {
  using Image = itk::Image<Pixel, 3>;
  if (data.size() != g.n_voxels())
    throw InvalidInput(file_name, "voxel array does not match the grid size",
                       "one value per voxel");
  auto io = image_io_for(file_name);
  auto image = allocate_image<Pixel>(g);
  std::copy(data.begin(), data.end(), image->GetBufferPointer());

  auto writer = itk::ImageFileWriter<Image>::New();
  writer->SetImageIO(io);
  writer->SetFileName(file_name);
  writer->SetInput(image);
  writer->SetUseCompression(true);
  try {
    writer->Update();
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(file_name, std::string("cannot write image: ") + e.GetDescription(),
                       "a writable path with extension " + accepted_image_formats());
  }
}

} // namespace

dealii::Point<3> VolumeGeometry::point(double i, double j, double k) const {
  const double idx[3] = {i * spacing[0], j * spacing[1], k * spacing[2]};
  dealii::Point<3> p;
  for (unsigned int r = 0; r < 3; ++r) {
    p[r] = origin[r];
    for (unsigned int c = 0; c < 3; ++c)
      p[r] += direction[r][c] * idx[c];
  }
  return p;
}

std::array<double, 3> VolumeGeometry::index_of(const dealii::Point<3>& x) const {
  dealii::Tensor<2, 3> A; // x = origin + A idx, A = direction diag(spacing)
  for (unsigned int r = 0; r < 3; ++r)
    for (unsigned int c = 0; c < 3; ++c)
      A[r][c] = direction[r][c] * spacing[c];
  dealii::Tensor<1, 3> d;
  for (unsigned int r = 0; r < 3; ++r)
    d[r] = x[r] - origin[r];
  const dealii::Tensor<1, 3> idx = dealii::invert(A) * d;
  return {{idx[0], idx[1], idx[2]}};
}

double VolumeGeometry::handedness() const {
  const auto& a = direction;
  const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  return det < 0 ? -1.0 : 1.0;
}

bool VolumeGeometry::same_grid(const VolumeGeometry& o, double tol) const {
  if (size != o.size)
    return false;
  const double h = std::min({spacing[0], spacing[1], spacing[2]});
  for (unsigned int d = 0; d < 3; ++d) {
    if (std::abs(spacing[d] - o.spacing[d]) > tol * h ||
        std::abs(origin[d] - o.origin[d]) > tol * h)
      return false;
    for (unsigned int c = 0; c < 3; ++c)
      if (std::abs(direction[d][c] - o.direction[d][c]) > tol)
        return false;
  }
  return true;
}

std::size_t LabelVolume::count(int label) const {
  return static_cast<std::size_t>(std::count(labels.begin(), labels.end(), label));
}

std::string accepted_image_formats() {
  return "a 3-D scalar image: NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr), MetaImage (.mha, "
         ".mhd), or a directory holding one DICOM series";
}

CtVolume read_ct_volume(const std::string& file_name) {
  CtVolume volume;
  auto image = read_double_image(file_name, volume);
  const double* data = image->GetBufferPointer();
  volume.values.assign(data, data + volume.n_voxels());
  for (std::size_t n = 0; n < volume.values.size(); ++n)
    if (!std::isfinite(volume.values[n]))
      throw InvalidInput(file_name, "voxel " + std::to_string(n) + " is not a finite number",
                         "finite voxel values");
  return volume;
}

LabelVolume read_label_volume(const std::string& file_name) {
  LabelVolume volume;
  auto image = read_double_image(file_name, volume);
  const double* data = image->GetBufferPointer();
  volume.labels.resize(volume.n_voxels());
  for (std::size_t n = 0; n < volume.labels.size(); ++n) {
    const double v = data[n];
    if (!(std::abs(v - std::round(v)) <= 1e-6) || std::abs(v) > 2e9) {
      std::ostringstream msg;
      msg << "voxel " << n << " holds the non-integral label " << v;
      throw InvalidInput(file_name, msg.str(), "integer labels (a segmentation, not a grey image)");
    }
    volume.labels[n] = static_cast<int>(std::lround(v));
  }
  return volume;
}

void write_ct_volume(const CtVolume& volume, const std::string& file_name) {
  write_image<double>(volume, volume.values, file_name);
}

void write_dicom_series(const CtVolume& volume, const std::string& directory,
                        const std::string& series_uid) {
  using Image = itk::Image<short, 3>;
  using Slice = itk::Image<short, 2>;
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(directory, ec);
  auto image = allocate_image<short>(volume);
  const auto spacing = image->GetSpacing();
  const auto direction = image->GetDirection();
  for (std::size_t n = 0; n < volume.values.size(); ++n) {
    const double v = std::round(volume.values[n]);
    if (!(v >= -32768 && v <= 32767))
      throw InvalidInput(directory, "value " + std::to_string(volume.values[n]) + " too large",
                         "values in [-32768, 32767] (DICOM's 16-bit pixels, slope 1)");
    image->GetBufferPointer()[n] = static_cast<short>(v);
  }
  // One dictionary per slice: the series' orientation and spacing, the slice's position.
  // DICOM decimal strings hold at most 16 characters: 10 digits, round-off zeroed.
  auto ds = [](double v) {
    std::ostringstream o;
    o << std::setprecision(10) << (std::abs(v) < 1e-12 ? 0.0 : v);
    return o.str();
  };
  const std::string orientation = ds(direction(0, 0)) + "\\" + ds(direction(1, 0)) + "\\" +
                                  ds(direction(2, 0)) + "\\" + ds(direction(0, 1)) + "\\" +
                                  ds(direction(1, 1)) + "\\" + ds(direction(2, 1));
  const std::string pixel_spacing = ds(spacing[1]) + "\\" + ds(spacing[0]);
  std::vector<std::unique_ptr<itk::MetaDataDictionary>> owned;
  itk::ImageSeriesReader<Image>::DictionaryArrayType dictionaries;
  std::vector<std::string> files;
  for (unsigned int k = 0; k < volume.size[2]; ++k) {
    owned.push_back(std::make_unique<itk::MetaDataDictionary>());
    auto& dict = *owned.back();
    Image::IndexType index;
    index[0] = 0;
    index[1] = 0;
    index[2] = k;
    Image::PointType position;
    image->TransformIndexToPhysicalPoint(index, position);
    const std::string pos = ds(position[0]) + "\\" + ds(position[1]) + "\\" + ds(position[2]);
    itk::EncapsulateMetaData<std::string>(dict, "0008|0060", "CT");
    itk::EncapsulateMetaData<std::string>(dict, "0020|0032", pos);
    itk::EncapsulateMetaData<std::string>(dict, "0020|0037", orientation);
    itk::EncapsulateMetaData<std::string>(dict, "0028|0030", pixel_spacing);
    itk::EncapsulateMetaData<std::string>(dict, "0018|0050", ds(spacing[2]));
    itk::EncapsulateMetaData<std::string>(dict, "0020|0013", std::to_string(k + 1));
    itk::EncapsulateMetaData<std::string>(dict, "0028|1052", "0");
    itk::EncapsulateMetaData<std::string>(dict, "0028|1053", "1");
    itk::EncapsulateMetaData<std::string>(dict, "0020|000e", series_uid);
    itk::EncapsulateMetaData<std::string>(dict, "0020|000d", "1.2.826.0.1.3680043.2.1125.1.2");
    dictionaries.push_back(&dict);
    char name[32];
    std::snprintf(name, sizeof name, "slice_%04u.dcm", k);
    files.push_back((fs::path(directory) / name).string());
  }
  auto io = itk::GDCMImageIO::New();
  io->KeepOriginalUIDOn();
  auto writer = itk::ImageSeriesWriter<Image, Slice>::New();
  writer->SetInput(image);
  writer->SetImageIO(io);
  writer->SetFileNames(files);
  writer->SetMetaDataDictionaryArray(&dictionaries);
  try {
    writer->Update();
  } catch (const itk::ExceptionObject& e) {
    throw InvalidInput(directory,
                       std::string("cannot write the DICOM series: ") + e.GetDescription(),
                       "a writable directory");
  }
}

void write_label_volume(const LabelVolume& volume, const std::string& file_name) {
  std::vector<short> data(volume.labels.size());
  for (std::size_t n = 0; n < data.size(); ++n) {
    if (volume.labels[n] < -32768 || volume.labels[n] > 32767)
      throw InvalidInput(file_name, "label " + std::to_string(volume.labels[n]) + " too large",
                         "labels in [-32768, 32767]");
    data[n] = static_cast<short>(volume.labels[n]);
  }
  write_image<short>(volume, data, file_name);
}

} // namespace spinesim::fem
