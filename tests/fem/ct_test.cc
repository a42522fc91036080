// CT volume -> hexahedral model (fem/ct): the verse004 data set's published grid and label
// counts, density-modulus laws against their formulas, reader round trips on synthetic
// volumes in every format, voxel meshing (counts, volume, components, orientation, ids),
// mass conservation under coarsening, and the mesh -> particle conversion's conservation.
#include "base/exceptions.h"
#include "fem/ct/ct_box.h"
#include "fem/ct/ct_cell_laws.h"
#include "fem/ct/ct_model.h"
#include "fem/ct/ct_parameters.h"
#include "fem/ct/ct_value_check.h"
#include "fem/ct/ct_volume.h"
#include "fem/ct/density_calibration.h"
#include "fem/ct/density_modulus_law.h"
#include "fem/ct/end_faces.h"
#include "fem/ct/mesh_to_particles.h"
#include "fem/ct/voxel_mesher.h"
#include "fem/materials/j2_plasticity.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/hdf5.h>
#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/grid/tria.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

using namespace dealii;
using namespace spinesim;
using namespace spinesim::fem;

namespace {

const std::string verse_dir = std::string(SPINESIM_SOURCE_DIR) + "/meshes/verse004";
const std::string verse_image = verse_dir + "/sub-verse004_0000_vertebra_21_im.nii.gz";
const std::string verse_labels = verse_dir + "/sub-verse004_0000_vertebra_21_seg.nii.gz";

// Scratch files of one test, in the build tree (tests run as separate processes).
std::string scratch(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(SPINESIM_CT_TEST_DIR) / "ct_data";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// A rotation about z by 30 degrees, so direction handling is tested off the identity.
std::array<std::array<double, 3>, 3> rotation_z30() {
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  return {{{{c, -s, 0}}, {{s, c, 0}}, {{0, 0, 1}}}};
}

// A cylinder of density 800 mg/cm^3 (axis along k, radius 5 voxels) in air (-1000), on an
// anisotropic, rotated, shifted grid.
CtVolume cylinder_volume() {
  CtVolume v;
  v.size = {{16, 14, 12}};
  v.spacing = {{0.5e-3, 0.6e-3, 0.7e-3}};
  v.origin = {{10e-3, -5e-3, 3e-3}};
  v.direction = rotation_z30();
  v.values.resize(v.n_voxels());
  for (unsigned int k = 0; k < v.size[2]; ++k)
    for (unsigned int j = 0; j < v.size[1]; ++j)
      for (unsigned int i = 0; i < v.size[0]; ++i) {
        const double x = i - 7.5, y = j - 6.5;
        // Fractional part makes the value pattern unique per voxel for the round trip.
        v.values[v.linear_index(i, j, k)] =
            (x * x + y * y <= 25 ? 800.0 : -1000.0) + 0.001 * (i + 16 * j + 224 * k);
      }
  return v;
}

void expect_same_geometry(const VolumeGeometry& a, const VolumeGeometry& b, double tol) {
  for (unsigned int d = 0; d < 3; ++d) {
    EXPECT_EQ(a.size[d], b.size[d]);
    EXPECT_NEAR(a.spacing[d], b.spacing[d], tol * a.spacing[d]) << "axis " << d;
    EXPECT_NEAR(a.origin[d], b.origin[d], tol * a.spacing[d]) << "axis " << d;
    for (unsigned int c = 0; c < 3; ++c)
      EXPECT_NEAR(a.direction[d][c], b.direction[d][c], tol) << d << "," << c;
  }
}

std::size_t count_if_labels(const LabelVolume& l, const std::set<int>& which) {
  std::size_t n = 0;
  for (int v : l.labels)
    n += which.count(v);
  return n;
}

} // namespace

// The data set's README states 100 x 89 x 74 voxels at 1 mm and these label counts.
TEST(CtVolume, ReadsVerse004GridAndLabelCounts) {
  const CtVolume image = read_ct_volume(verse_image);
  const LabelVolume labels = read_label_volume(verse_labels);
  EXPECT_EQ(image.size, (std::array<unsigned int, 3>{{100, 89, 74}}));
  for (unsigned int d = 0; d < 3; ++d)
    EXPECT_NEAR(image.spacing[d], 1e-3, 1e-9); // float32 header precision
  EXPECT_TRUE(labels.same_grid(image));
  const std::size_t expected[6] = {22553, 11093, 7761, 12343, 7015, 6425};
  for (int l = 1; l <= 6; ++l)
    EXPECT_EQ(labels.count(l), expected[l - 1]) << "label " << l;
  // README: range about -214 ... 1894 mg/cm^3.
  const auto [lo, hi] = std::minmax_element(image.values.begin(), image.values.end());
  EXPECT_NEAR(*lo, -214, 5);
  EXPECT_NEAR(*hi, 1894, 5);
  // Index -> point: the affine map of the header (voxel (1,0,0) is one spacing along axis 0).
  const Point<3> p0 = image.point(0, 0, 0), p1 = image.point(1, 0, 0);
  EXPECT_NEAR(p0.distance(p1), image.spacing[0], 1e-12);
  for (unsigned int d = 0; d < 3; ++d)
    EXPECT_NEAR(p0[d], image.origin[d], 1e-15);
  // Point -> index inverts it (the header's direction matrix included), to round-off.
  const auto idx = image.index_of(image.point(12.25, 40, 73.5));
  EXPECT_NEAR(idx[0], 12.25, 1e-9);
  EXPECT_NEAR(idx[1], 40, 1e-9);
  EXPECT_NEAR(idx[2], 73.5, 1e-9);
}

TEST(CtVolume, MissingOrUnknownFilesAreInvalidInput) {
  try {
    read_ct_volume(verse_dir + "/does_not_exist.nii.gz");
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.where().find("does_not_exist.nii.gz"), std::string::npos);
    EXPECT_NE(e.allowed().find(".nrrd"), std::string::npos);
  }
  const std::string bad = scratch("not_an_image.nii");
  std::ofstream(bad) << "plain text, not NIfTI";
  EXPECT_THROW(read_ct_volume(bad), InvalidInput);
  const std::string txt = verse_dir + "/sub-verse004_0000_calibration.txt";
  try {
    read_ct_volume(txt);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.where().find("calibration.txt"), std::string::npos);
  }
  // A grey image is not a label map.
  const CtVolume cyl = cylinder_volume();
  write_ct_volume(cyl, scratch("cyl_grey.nrrd"));
  EXPECT_THROW(read_label_volume(scratch("cyl_grey.nrrd")), InvalidInput);
}

// Every reader round-trips geometry and values of a volume written by ITK.
TEST(CtVolume, SyntheticCylinderRoundTripsInAllFormats) {
  const CtVolume original = cylinder_volume();
  for (const std::string ext : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd"}) {
    const std::string file = scratch("cylinder" + ext);
    write_ct_volume(original, file);
    const CtVolume back = read_ct_volume(file);
    SCOPED_TRACE(ext);
    // NIfTI stores spacing, origin and the orientation in float32: 1e-6 relative covers it.
    expect_same_geometry(original, back, 1e-6);
    ASSERT_EQ(back.values.size(), original.values.size());
    double max_error = 0;
    for (std::size_t n = 0; n < back.values.size(); ++n)
      max_error = std::max(max_error, std::abs(back.values[n] - original.values[n]));
    EXPECT_EQ(max_error, 0.0); // float64 pixels are stored exactly in every format
    // Physical position of a voxel survives (to float32 header precision, 1 nm here).
    EXPECT_LT(back.point(3, 4, 5).distance(original.point(3, 4, 5)), 1e-9);
  }
  // Labels as integers, in a second format.
  LabelVolume labels;
  static_cast<VolumeGeometry&>(labels) = original;
  labels.labels.resize(original.n_voxels());
  for (std::size_t n = 0; n < labels.labels.size(); ++n)
    labels.labels[n] = original.values[n] > 0 ? 3 : 0;
  write_label_volume(labels, scratch("cylinder_labels.mha"));
  const LabelVolume back = read_label_volume(scratch("cylinder_labels.mha"));
  EXPECT_EQ(back.labels, labels.labels);
  // 81 voxels per slice lie in x^2 + y^2 <= 25 on the half-integer grid: counted directly.
  std::size_t per_slice = 0;
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 14; ++j)
      per_slice += (i - 7.5) * (i - 7.5) + (j - 6.5) * (j - 6.5) <= 25;
  EXPECT_EQ(back.count(3), per_slice * 12);
}

// A DICOM series (a directory, read through GDCM): verse004 written slice by slice reads back
// on the same grid with its values rounded to DICOM's integers, and a series with a missing
// slice, two series in one directory, or an empty directory are bad input naming them.
TEST(CtVolume, DicomSeriesReadsLikeTheNifti) {
  namespace fs = std::filesystem;
  const CtVolume image = read_ct_volume(verse_image);
  const std::string dir = scratch("verse004_dicom");
  fs::remove_all(dir);
  write_dicom_series(image, dir);
  ASSERT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 74);
  const CtVolume back = read_ct_volume(dir);
  // DICOM keeps positions and spacing as decimal strings of 12 digits: 1e-6 relative is ample.
  expect_same_geometry(image, back, 1e-6);
  ASSERT_EQ(back.values.size(), image.values.size());
  double max_error = 0;
  for (std::size_t n = 0; n < back.values.size(); ++n)
    max_error = std::max(max_error, std::abs(back.values[n] - image.values[n]));
  // 16-bit integer pixels with slope 1: each value within half a unit (mg/cm^3) of the NIfTI's.
  EXPECT_LE(max_error, 0.5 + 1e-9);
  EXPECT_GT(max_error, 0.0) << "the NIfTI holds fractional values";

  // An anisotropic, rotated grid whose files are named against their order: the reader sorts
  // by position, and the pixel spacing (row, then column in DICOM) lands on the right axes.
  // Every voxel within half a unit: the values grow by 0.224 a slice, so a slice out of place
  // would miss by more.
  const CtVolume cylinder = cylinder_volume();
  const std::string cyl_dir = scratch("cylinder_dicom");
  fs::remove_all(cyl_dir);
  write_dicom_series(cylinder, cyl_dir);
  for (unsigned int k = 0; k < cylinder.size[2]; ++k) {
    char from[32], to[32];
    std::snprintf(from, sizeof from, "slice_%04u.dcm", k);
    std::snprintf(to, sizeof to, "renamed_%04u.dcm", cylinder.size[2] - 1 - k);
    fs::rename(fs::path(cyl_dir) / from, fs::path(cyl_dir) / to);
  }
  const CtVolume cyl_back = read_ct_volume(cyl_dir);
  expect_same_geometry(cylinder, cyl_back, 1e-6);
  ASSERT_EQ(cyl_back.values.size(), cylinder.values.size());
  double cyl_error = 0;
  for (std::size_t n = 0; n < cyl_back.values.size(); ++n)
    cyl_error = std::max(cyl_error, std::abs(cyl_back.values[n] - cylinder.values[n]));
  EXPECT_LE(cyl_error, 0.5 + 1e-9);
  fs::remove_all(cyl_dir);

  auto message_of = [](const std::string& d) {
    try {
      read_ct_volume(d);
    } catch (const InvalidInput& e) {
      return e.where() + " | " + e.problem();
    }
    return std::string("no InvalidInput");
  };
  // A slice gone from the middle: the volume would be stretched silently.
  const std::string gap = scratch("verse004_dicom_gap");
  fs::remove_all(gap);
  fs::copy(dir, gap);
  fs::remove(fs::path(gap) / "slice_0030.dcm");
  const std::string m1 = message_of(gap);
  EXPECT_NE(m1.find("slices are missing or unevenly spaced"), std::string::npos) << m1;
  // Two series in one directory (another Series Instance UID).
  const std::string other = scratch("verse004_dicom_other");
  fs::remove_all(other);
  write_dicom_series(image, other, "1.2.826.0.1.3680043.2.1125.1.3");
  const std::string two = scratch("verse004_dicom_two");
  fs::remove_all(two);
  fs::copy(dir, two);
  for (const std::string name : {"slice_0000.dcm", "slice_0001.dcm", "slice_0002.dcm"})
    fs::copy_file(fs::path(other) / name, fs::path(two) / ("other_" + name));
  const std::string m2 = message_of(two);
  EXPECT_NE(m2.find("2 DICOM series in one directory"), std::string::npos) << m2;
  EXPECT_NE(m2.find("1.2.826.0.1.3680043.2.1125.1.3"), std::string::npos) << m2;
  const std::string empty = scratch("verse004_dicom_empty");
  fs::remove_all(empty);
  fs::create_directories(empty);
  const std::string m3 = message_of(empty);
  EXPECT_NE(m3.find("no DICOM series"), std::string::npos) << m3;
  EXPECT_NE(m3.find(empty), std::string::npos) << m3;
  fs::remove_all(dir);
  fs::remove_all(gap);
  fs::remove_all(other);
  fs::remove_all(two);
  fs::remove_all(empty);
}

TEST(CtDensityCalibration, DensityAndHounsfieldUnits) {
  const DensityCalibration mg(DensityCalibration::ValueType::density, 0, 0);
  EXPECT_DOUBLE_EQ(mg.density(250.0), 0.25); // mg/cm^3 -> g/cm^3
  // verse004 record: material density = 0.968731 + 0.000893 HU [g/cm^3].
  const DensityCalibration hu(DensityCalibration::ValueType::hu, 0.968731, 0.000893);
  for (double v : {-1000.0, 0.0, 1226.214})
    EXPECT_DOUBLE_EQ(hu.density(v), 0.968731 + 0.000893 * v);
  EXPECT_THROW(DensityCalibration(DensityCalibration::ValueType::hu, 0, -1), InvalidInput);
  EXPECT_THROW(DensityCalibration::parse_value_type("grey"), InvalidInput);
}

// A complete file that holds nothing usable is bad input naming the file and the voxel; a
// volume with contrast passes.
TEST(CtValueCheck, BlankOrNonFiniteImagesAreInvalidInput) {
  CtVolume image;
  image.file_name = "scan.nii";
  image.size = {{3, 2, 2}};
  image.values.assign(12, 0.0);
  try {
    check_image_values(image);
    FAIL() << "a blank image passed";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "CT/Image file");
    EXPECT_NE(e.problem().find("scan.nii: all 12 voxels hold the value 0"), std::string::npos)
        << e.problem();
  }
  image.values[7] = 250.0;
  EXPECT_NO_THROW(check_image_values(image));
  image.values[10] = std::numeric_limits<double>::quiet_NaN(); // voxel (1, 1, 1)
  try {
    check_image_values(image);
    FAIL() << "a NaN voxel passed";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.problem().find("voxel (1, 1, 1) holds nan"), std::string::npos) << e.problem();
  }
}

// Densities bone can have give no warning; each implausible pattern gives its own.
TEST(CtValueCheck, ImplausibleBoneDensitiesAreWarnings) {
  // Trabecular to cortical (g/cm^3), a few noisy cells below zero: plausible.
  EXPECT_TRUE(bone_density_warnings({-0.02, 0.08, 0.15, 0.3, 1.1, 1.9}, "a.nii").empty());
  EXPECT_TRUE(bone_density_warnings({}, "a.nii").empty());
  const auto dense = bone_density_warnings({0.1, 0.2, 2.5, 9.0}, "a.nii");
  ASSERT_EQ(dense.size(), 1u);
  EXPECT_NE(dense[0].find("2 of 4 bone cells (50 %) are denser than 2.2 g/cm^3"), std::string::npos)
      << dense[0];
  const auto negative = bone_density_warnings({-0.3, -0.2, -0.1, 0.2}, "a.nii");
  ASSERT_EQ(negative.size(), 1u);
  EXPECT_NE(negative[0].find("3 of 4 bone cells (75 %) have a negative"), std::string::npos);
  const auto flat = bone_density_warnings({0.969, 0.970, 0.971}, "a.nii");
  ASSERT_EQ(flat.size(), 1u);
  EXPECT_NE(flat[0].find("no bone contrast"), std::string::npos);
}

// Each law at a few densities against its formula written out here (MPa -> Pa).
TEST(CtDensityModulusLaw, MatchesPublishedFormulas) {
  for (const double rho : {0.05, 0.15, 0.3, 0.8, 1.5}) {
    const DensityModulusLaw morgan("morgan2003_vertebra", 0, 1e-3, 1.0);
    const DensityModulusLaw kopperdahl("kopperdahl2002", 0, 1e-3, 1.0);
    const DensityModulusLaw crawford("crawford2003", 0, 1e-3, 1.0);
    const DensityModulusLaw constant("constant", 2.5e9, 1e-3, 1.0);
    // Relative 1e-14: same formula, only the evaluation order may differ.
    EXPECT_NEAR(morgan.modulus(rho), 1e6 * 4730 * std::exp(1.56 * std::log(rho)),
                1e-14 * morgan.modulus(rho));
    EXPECT_NEAR(kopperdahl.modulus(rho), 1e6 * 2980 * std::exp(1.05 * std::log(rho)),
                1e-14 * kopperdahl.modulus(rho));
    EXPECT_NEAR(kopperdahl.yield_stress(rho), 1e6 * 37.4 * std::exp(1.39 * std::log(rho)),
                1e-14 * kopperdahl.yield_stress(rho));
    EXPECT_NEAR(crawford.modulus(rho), 1e6 * (3230 * rho - 34.7), 1e-6);
    EXPECT_EQ(constant.modulus(rho), 2.5e9);
    EXPECT_FALSE(morgan.has_yield_stress());
    EXPECT_THROW(morgan.yield_stress(rho), InvalidInput);
  }
  EXPECT_THROW(DensityModulusLaw("carter1977", 0, 1e-3, 1e6), InvalidInput);
  EXPECT_THROW(DensityModulusLaw("constant", 0, 1e-3, 1e6), InvalidInput);
  EXPECT_THROW(DensityModulusLaw("crawford2003", 0, 1e-3, 0), InvalidInput);
}

TEST(CtDensityModulusLaw, FloorsAreAppliedAndCounted) {
  const std::vector<double> rho = {-0.2, 0.0, 0.005, 0.3, 0.02};
  // crawford2003 is negative below 34.7/3230 = 0.01074 g/cm^3: -0.2, 0 (raised to 0.001) and
  // 0.005 hit the 1 MPa modulus floor; the first two also the density floor.
  const DensityModulusLaw crawford("crawford2003", 0, 1e-3, 1e6);
  const auto c = crawford.evaluate(rho);
  EXPECT_EQ(c.floored_density, 2u);
  EXPECT_EQ(c.floored_modulus, 3u);
  EXPECT_EQ(c.floored_cells, 3u);
  EXPECT_EQ(c.modulus[0], 1e6);
  EXPECT_NEAR(c.modulus[3], 1e6 * (3230 * 0.3 - 34.7), 1e-6);
  EXPECT_NEAR(c.modulus[4], 1e6 * (3230 * 0.02 - 34.7), 1e-6);
  // morgan2003 with density floor 0.01: the floored cells take E(0.01) = 3.59 MPa > 1 MPa.
  const DensityModulusLaw morgan("morgan2003_vertebra", 0, 0.01, 1e6);
  const auto m = morgan.evaluate(rho);
  EXPECT_EQ(m.floored_density, 3u);
  EXPECT_EQ(m.floored_modulus, 0u);
  EXPECT_EQ(m.floored_cells, 3u);
  EXPECT_NEAR(m.modulus[0], 1e6 * 4730 * std::pow(0.01, 1.56), 1e-6);
  EXPECT_NEAR(m.modulus[2], m.modulus[0], 0.0);
  for (double e : m.modulus)
    EXPECT_TRUE(e >= 1e6 && std::isfinite(e));
  EXPECT_THROW(morgan.evaluate({std::nan("")}), NumericalFailure);
}

namespace {

// 12 x 10 x 9 grid: a 5x4x6 block of label 1 with a 2x4x1 layer of label 2 on its top face,
// one isolated label-1 voxel far away and a label-7 voxel (not selected) touching the block.
LabelVolume block_labels(const VolumeGeometry& g) {
  LabelVolume l;
  static_cast<VolumeGeometry&>(l) = g;
  l.labels.assign(g.n_voxels(), 0);
  for (unsigned int k = 1; k < 7; ++k)
    for (unsigned int j = 2; j < 6; ++j)
      for (unsigned int i = 3; i < 8; ++i)
        l.labels[g.linear_index(i, j, k)] = 1;
  for (unsigned int j = 2; j < 6; ++j)
    for (unsigned int i = 3; i < 5; ++i)
      l.labels[g.linear_index(i, j, 7)] = 2;
  l.labels[g.linear_index(10, 8, 8)] = 1;
  l.labels[g.linear_index(8, 3, 3)] = 7;
  return l;
}

VolumeGeometry block_grid(bool flip) {
  VolumeGeometry g;
  g.size = {{12, 10, 9}};
  g.spacing = {{0.4e-3, 0.5e-3, 0.6e-3}};
  g.origin = {{-2e-3, 1e-3, 4e-3}};
  if (flip) // LPS-style flipped axis: left-handed image frame
    g.direction = {{{{1, 0, 0}}, {{0, -1, 0}}, {{0, 0, 1}}}};
  return g;
}

} // namespace

// Factor 1: one cell per selected voxel, exact volume, largest component, orientation, ids.
TEST(CtVoxelMesher, LabelMeshCountsVolumeComponentsAndIds) {
  for (const bool flip : {false, true}) {
    SCOPED_TRACE(flip ? "flipped axis" : "identity direction");
    const VolumeGeometry grid = block_grid(flip);
    const LabelVolume labels = block_labels(grid);
    std::vector<double> rho(grid.n_voxels());
    for (std::size_t n = 0; n < rho.size(); ++n)
      rho[n] = 0.1 + 1e-4 * n; // distinct per voxel
    VoxelMesher::Options options;
    options.labels = {1, 2};
    options.label_boundary_ids = {{2, 7}};
    const std::size_t selected = count_if_labels(labels, {1, 2});
    ASSERT_EQ(selected, 5u * 4 * 6 + 2 * 4 + 1);

    Triangulation<3> tria;
    const VoxelMesh mesh = VoxelMesher(grid, rho, &labels, options).build(tria);
    EXPECT_EQ(mesh.n_selected_voxels, selected);
    EXPECT_EQ(mesh.n_components, 2u);
    EXPECT_EQ(mesh.n_dropped_cells, 1u); // the isolated voxel
    EXPECT_EQ(tria.n_active_cells(), selected - 1);
    const double voxel_volume = grid.voxel_volume();
    // Volume: sum of exact cell measures = count x voxel volume (round-off, 1e-12 relative).
    double volume = 0, mass = 0;
    for (const auto& cell : tria.active_cell_iterators()) {
      EXPECT_GT(cell->measure(), 0); // right-handed even for the flipped frame
      volume += cell->measure();
      // The cell centre is the centre of the voxel its density came from.
      const auto& v = mesh.cell_first_voxel[cell->id().get_coarse_cell_id()];
      EXPECT_LT(cell->center().distance(grid.point(v[0], v[1], v[2])), 1e-12);
      EXPECT_DOUBLE_EQ(mesh.density(cell), rho[grid.linear_index(v[0], v[1], v[2])]);
      EXPECT_EQ(int(cell->material_id()), labels.label(v[0], v[1], v[2]));
      mass += 1000 * mesh.density(cell) * cell->measure();
      for (const unsigned int f : cell->face_indices())
        if (cell->face(f)->at_boundary()) {
          EXPECT_EQ(cell->face(f)->boundary_id(), cell->material_id() == 2 ? 7 : 0);
        }
    }
    EXPECT_NEAR(volume, (selected - 1) * voxel_volume, 1e-12 * volume);
    EXPECT_NEAR(mesh.total_volume(), volume, 1e-12 * volume);
    EXPECT_NEAR(mesh.total_mass(), mass, 1e-12 * mass);
    // Watertight surface: the 5x4x6 box (2 (20 + 24 + 30) faces) with the 2x4x1 layer on top
    // (covers 8 top faces, adds 8 top and 2 (2 + 4) side faces); the label-7 voxel is not meshed.
    unsigned int boundary_faces = 0;
    for (const auto& cell : tria.active_cell_iterators())
      for (const unsigned int f : cell->face_indices())
        boundary_faces += cell->face(f)->at_boundary();
    EXPECT_EQ(boundary_faces, 2u * (5 * 4 + 4 * 6 + 5 * 6) - 8 + 8 + 2 * (2 + 4));

    // End faces along z: the bottom of the block (20 faces) and the label-2 layer on top (8).
    const EndFaceCount ends = mark_end_faces<3>(tria);
    EXPECT_EQ(ends.lower, 20u);
    EXPECT_EQ(ends.upper, 8u);
    const auto [zmin, zmax] = extent_along<3>(tria, 2);
    EXPECT_NEAR(zmax - zmin, 7 * grid.spacing[2], 1e-12);
    EXPECT_EQ(cells_in_slab<3>(tria, 2, zmax - grid.spacing[2], zmax).size(), 8u);

    // Without the component filter the isolated voxel stays.
    options.keep_largest_component = false;
    Triangulation<3> all;
    const VoxelMesh unfiltered = VoxelMesher(grid, rho, &labels, options).build(all);
    EXPECT_EQ(all.n_active_cells(), selected);
    EXPECT_EQ(unfiltered.n_dropped_cells, 0u);
  }
}

// Cells meeting only along an edge or at a corner make p4est abort on refinement; the mesher
// fills one block per such contact so the distributed mesh refines.
TEST(CtVoxelMesher, RepairsEdgeAndCornerContactsForP4est) {
  VolumeGeometry g;
  g.size = {{4, 4, 4}};
  g.spacing = {{1e-3, 1e-3, 1e-3}};
  for (const bool corner : {false, true}) {
    SCOPED_TRACE(corner ? "corner contact" : "edge contact");
    LabelVolume l;
    static_cast<VolumeGeometry&>(l) = g;
    l.labels.assign(g.n_voxels(), 0);
    // Edge: (0,0,0) and (1,1,0) share only an edge, joined through the layer above.
    // Corner: (0,0,0) and (1,1,1) share only a corner, joined through a path at z = 2.
    const std::vector<std::array<unsigned int, 3>> edge = {
        {{0, 0, 0}}, {{1, 1, 0}}, {{0, 0, 1}}, {{1, 0, 1}}, {{1, 1, 1}}};
    const std::vector<std::array<unsigned int, 3>> vertex = {{{0, 0, 0}}, {{1, 1, 1}}, {{0, 0, 1}},
                                                             {{0, 0, 2}}, {{0, 1, 2}}, {{1, 1, 2}}};
    for (const auto& v : corner ? vertex : edge)
      l.labels[g.linear_index(v[0], v[1], v[2])] = 1;
    std::vector<double> rho(g.n_voxels(), 0.5);
    VoxelMesher::Options options;
    options.labels = {1};
    parallel::distributed::Triangulation<3> tria(MPI_COMM_WORLD);
    const VoxelMesh mesh = VoxelMesher(g, rho, &l, options).build(tria);
    EXPECT_EQ(mesh.n_added_cells, 1u);
    EXPECT_EQ(tria.n_global_active_cells(), (corner ? vertex : edge).size() + 1);
    EXPECT_EQ(mesh.n_components, 1u);
    tria.refine_global(1); // aborts inside p4est without the repair
    EXPECT_EQ(tria.n_global_active_cells(), 8 * ((corner ? vertex : edge).size() + 1));
  }
}

TEST(CtVoxelMesher, ThresholdModeAndErrors) {
  const CtVolume cyl = cylinder_volume();
  const DensityCalibration calibration(DensityCalibration::ValueType::density, 0, 0);
  VoxelMesher::Options options;
  options.density_threshold = 0.5; // g/cm^3: the 800 mg/cm^3 cylinder, not the air
  Triangulation<3> tria;
  const VoxelMesh mesh = VoxelMesher(cyl, calibration.densities(cyl), nullptr, options).build(tria);
  std::size_t expected = 0;
  for (double v : cyl.values)
    expected += v >= 500;
  EXPECT_EQ(tria.n_active_cells(), expected);
  for (const auto& cell : tria.active_cell_iterators())
    EXPECT_EQ(cell->material_id(), 0);
  // Mean density ~0.8 g/cm^3 plus the tiny per-voxel offsets (< 2.7e-3).
  EXPECT_NEAR(mesh.total_mass() / mesh.total_volume(), 800, 3);

  options.density_threshold = 5; // nothing that dense
  Triangulation<3> empty;
  EXPECT_THROW(VoxelMesher(cyl, calibration.densities(cyl), nullptr, options).build(empty),
               InvalidInput);
  options.labels = {1};
  EXPECT_THROW(VoxelMesher(cyl, calibration.densities(cyl), nullptr, options), InvalidInput);
}

// Coarsening by 2 on the bone labels 1-4 of verse004 keeps the bone mass to 1 %, on a
// parallel::distributed mesh; particles from it conserve volume and mass to round-off.
TEST(CtVoxelMesher, CoarseningKeepsVerse004BoneMassAndParticlesConserve) {
  const CtVolume image = read_ct_volume(verse_image);
  const LabelVolume labels = read_label_volume(verse_labels);
  // Independent bone mass: sum over labelled voxels of rho [g/cm^3] x 1 mm^3 -> kg.
  double bone_mass = 0;
  std::size_t bone_voxels = 0;
  for (std::size_t n = 0; n < image.values.size(); ++n)
    if (labels.labels[n] >= 1 && labels.labels[n] <= 4) {
      bone_mass += image.values[n] * 1e-3 /*g/cm^3*/ * 1e-3 /*cm^3*/ * 1e-3 /*kg/g*/;
      ++bone_voxels;
    }
  EXPECT_EQ(bone_voxels, 22553u + 11093 + 7761 + 12343);
  const DensityCalibration calibration(DensityCalibration::ValueType::density, 0, 0);
  VoxelMesher::Options options;
  options.labels = {1, 2, 3, 4};
  options.coarsening_factor = 2;
  parallel::distributed::Triangulation<3> tria(MPI_COMM_WORLD);
  const VoxelMesh mesh =
      VoxelMesher(image, calibration.densities(image), &labels, options).build(tria);
  EXPECT_NEAR(mesh.selected_mass, bone_mass, 1e-12 * bone_mass);
  // Mass of the coarse model vs. the voxels: the 1 % requirement of the voxel-to-FE step.
  EXPECT_NEAR(mesh.total_mass(), bone_mass, 0.01 * bone_mass)
      << "coarse " << mesh.total_mass() << " kg vs voxels " << bone_mass << " kg";
  // Each coarse cell covers 8 voxels (or fewer at the image edge): about 1/8 of the count.
  EXPECT_NEAR(double(tria.n_global_active_cells()), bone_voxels / 8.0, 0.15 * bone_voxels / 8);
  std::cout << "[ct] f=2: cells " << tria.n_global_active_cells() << ", mass "
            << mesh.total_mass() * 1e3 << " g vs voxels " << bone_mass * 1e3 << " g, volume "
            << mesh.total_volume() * 1e6 << " cm^3 vs " << mesh.selected_volume * 1e6
            << " cm^3, dropped " << mesh.n_dropped_cells << "\n";

  // Particles: one refinement first, so cells map to coarse ids through their parents.
  tria.refine_global(1);
  for (const auto placement : {ParticlePlacement::cell_centre, ParticlePlacement::gauss_points}) {
    const ParticleCloud<3> cloud = mesh_to_particles<3>(tria, mesh.cell_density, placement);
    double v = 0, m = 0;
    for (std::size_t p = 0; p < cloud.size(); ++p) {
      v += cloud.volumes[p];
      m += 1000 * cloud.density[p] * cloud.volumes[p];
    }
    v = Utilities::MPI::sum(v, MPI_COMM_WORLD);
    m = Utilities::MPI::sum(m, MPI_COMM_WORLD);
    // Parallelepiped cells: Gauss JxW sums are exact, so only summation round-off remains,
    // bounded by (terms) x machine epsilon relative.
    const double round_off = 4.0 * double(tria.n_global_active_cells()) * 8 * 2.2e-16;
    EXPECT_NEAR(v, mesh.total_volume(), round_off * v);
    EXPECT_NEAR(m, mesh.total_mass(), round_off * m);
    EXPECT_EQ(Utilities::MPI::sum(cloud.size(), MPI_COMM_WORLD),
              tria.n_global_active_cells() * (placement == ParticlePlacement::cell_centre ? 1 : 8));
  }
}

// HDF5 and VTU output: the file holds what was converted.
TEST(CtMeshToParticles, WritesHdf5AndVtu) {
  const VolumeGeometry grid = block_grid(false);
  const LabelVolume labels = block_labels(grid);
  std::vector<double> rho(grid.n_voxels(), 0.4);
  VoxelMesher::Options options;
  options.labels = {1, 2};
  Triangulation<3> tria;
  const VoxelMesh mesh = VoxelMesher(grid, rho, &labels, options).build(tria);
  const auto cloud = mesh_to_particles<3>(tria, mesh.cell_density, ParticlePlacement::gauss_points);
  const std::string h5 = scratch("particles.h5"), vtu = scratch("particles.vtu");
  write_particles_hdf5(cloud, h5);
  write_particles_vtu(cloud, vtu);

  HDF5::File file(h5, HDF5::File::FileAccessMode::open);
  const auto volumes = file.open_dataset("volumes").read<std::vector<double>>();
  const auto density = file.open_dataset("density").read<std::vector<double>>();
  const auto material = file.open_dataset("material_id").read<std::vector<unsigned int>>();
  auto positions_set = file.open_dataset("positions");
  EXPECT_EQ(positions_set.get_dimensions(), (std::vector<hsize_t>{cloud.size(), 3}));
  const auto positions = positions_set.read<std::vector<double>>();
  ASSERT_EQ(volumes.size(), 8 * tria.n_active_cells());
  EXPECT_EQ(volumes, cloud.volumes);
  EXPECT_EQ(density, cloud.density);
  EXPECT_EQ(material, cloud.material_id);
  for (std::size_t p = 0; p < cloud.size(); ++p)
    for (unsigned int d = 0; d < 3; ++d)
      ASSERT_EQ(positions[3 * p + d], cloud.positions[p][d]);
  EXPECT_NEAR(std::accumulate(volumes.begin(), volumes.end(), 0.0), mesh.total_volume(),
              1e-12 * mesh.total_volume()); // round-off only

  std::ifstream in(vtu);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("NumberOfPoints=\"" + std::to_string(cloud.size()) + "\""),
            std::string::npos);
  EXPECT_NE(text.find("Name=\"material_id\""), std::string::npos);
}

// Parameters: declare/parse in a subsection, relative paths against the scene directory, and
// the whole pipeline on verse004 with the caps as end faces.
TEST(CtParameters, ParseResolveAndBuildVerse004Model) {
  ParameterHandler prm;
  prm.enter_subsection("CT");
  CtParameters::declare(prm);
  prm.leave_subsection();
  prm.parse_input_from_string(
      "subsection CT\n"
      "  set Image file = verse004/sub-verse004_0000_vertebra_21_im.nii.gz\n"
      "  set Label file = verse004/sub-verse004_0000_vertebra_21_seg.nii.gz\n"
      "  set Labels = 1, 2, 3, 4, 5, 6\n"
      "  set Coarsening factor = 3\n"
      "  set Density modulus law = kopperdahl2002\n"
      "  set End face labels = 5, 6\n"
      "  set Label moduli = 5: 2.5e9, 6: 2.5e9\n"
      "  set Label densities = 5: 1.18, 6: 1.18\n"
      "end\n");
  prm.enter_subsection("CT");
  CtParameters p;
  p.parse(prm, std::string(SPINESIM_SOURCE_DIR) + "/meshes");
  prm.leave_subsection();
  EXPECT_EQ(p.image_file, verse_image);
  EXPECT_EQ(p.labels, (std::vector<int>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(CtParameters::resolve_path("/abs/x.nii", "/base"), "/abs/x.nii");

  parallel::distributed::Triangulation<3> tria(MPI_COMM_WORLD);
  const CtModel model = build_ct_model(p, tria);
  EXPECT_EQ(model.cell_modulus.size(), tria.n_cells(0));
  // A real calibrated vertebra raises none of the value warnings.
  EXPECT_TRUE(model.warnings.empty()) << model.warnings.front();
  // PMMA end caps: label 5 at low z (voxels k = 23..30), label 6 at high z (k = 52..59); the
  // posterior elements reach beyond them (k = 14..62), so the caps' own extremes are used.
  EXPECT_GT(model.end_faces.lower, 0u);
  EXPECT_GT(model.end_faces.upper, 0u);
  const Point<3> o = read_ct_volume(verse_image).point(0, 0, 0);
  double lower_area = 0, upper_area = 0;
  for (const auto& cell : tria.cell_iterators_on_level(0)) {
    for (const unsigned int f : cell->face_indices())
      if (cell->face(f)->at_boundary()) {
        if (cell->face(f)->boundary_id() == 4) {
          EXPECT_EQ(cell->material_id(), 5);
          // Cells of factor 3 start at voxel 0, so the cap bottom (k = 23) rounds to the
          // block boundary k = 21 - 1/2 or 24 - 1/2: the face lies at z = o + 20.5 or 23.5 mm.
          const double k = (cell->face(f)->center()[2] - o[2]) / 1e-3;
          EXPECT_TRUE(std::abs(k - 20.5) < 1e-6 || std::abs(k - 23.5) < 1e-6) << k;
          lower_area += cell->face(f)->measure();
        }
        if (cell->face(f)->boundary_id() == 5) {
          EXPECT_EQ(cell->material_id(), 6);
          upper_area += cell->face(f)->measure();
        }
      }
    EXPECT_GE(model.modulus(cell), 1e6);
    if (cell->material_id() >= 5) { // PMMA caps: the image holds 0 there, the labels decide
      EXPECT_EQ(model.modulus(cell), 2.5e9);
      EXPECT_EQ(model.mesh.density(cell), 1.18);
    } else {
      EXPECT_DOUBLE_EQ(
          model.modulus(cell),
          DensityModulusLaw("kopperdahl2002", 0, 1e-3, 1e6).modulus(model.mesh.density(cell)));
    }
  }
  // The caps cover the body's end plates: several cm^2 each (L2 end plate about 15 cm^2).
  EXPECT_GT(lower_area, 5e-4);
  EXPECT_GT(upper_area, 5e-4);
  std::cout << model.summary() << "\n[ct] cap end-face area lower " << lower_area * 1e4
            << " cm^2, upper " << upper_area * 1e4 << " cm^2\n";

  // Errors name the parameter.
  prm.enter_subsection("CT");
  prm.set("Label file", "");
  try {
    p.parse(prm);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "Label file");
  }
  prm.set("Labels", "");
  prm.set("Image file", "");
  EXPECT_THROW(p.parse(prm), InvalidInput);
  prm.leave_subsection();
}

// Per-cell laws: E, nu, mass density and (J2 kind) the yield stress of every coarse cell
// follow its density through the laws; labelled caps stay elastic with their own nu.
TEST(CtCellLaws, FollowTheDensityAndKeepCapsElastic) {
  CtModel model;
  model.mesh.cell_density = {0.2, 0.5, 1.18};
  model.mesh.cell_volume = {1e-9, 1e-9, 1e-9};
  model.cell_label = {1, 2, 5};
  const DensityModulusLaw law("kopperdahl2002", 0, 1e-3, 1e6);
  model.cell_modulus = {law.modulus(0.2), law.modulus(0.5), 3e9};
  model.poisson_ratio = 0.3;
  CtCellLaws::Options o;
  o.kind = CtCellLaws::Kind::j2_plasticity;
  o.label_poisson_ratio[5] = 0.35;
  o.elastic_labels = {5};
  o.hardening_ratio = 0.05;
  const CtCellLaws laws(model, o);
  ASSERT_EQ(laws.size(), 3u);
  EXPECT_EQ(laws.n_plastic_cells(), 2u);
  for (unsigned int c = 0; c < 2; ++c) {
    const double rho = model.mesh.cell_density[c];
    EXPECT_EQ(laws.law(c)->name(), "j2_plasticity");
    EXPECT_EQ(laws.law(c)->youngs_modulus(), model.cell_modulus[c]);
    EXPECT_EQ(laws.law(c)->poisson_ratio(), 0.3);
    EXPECT_DOUBLE_EQ(laws.law(c)->density(), 1000 * rho);
    // Relative 1e-14: the same formula as the published one, evaluated in another order.
    EXPECT_NEAR(laws.yield_stress(c), 37.4e6 * std::pow(rho, 1.39), 1e-14 * laws.yield_stress(c));
    const auto& j2 = dynamic_cast<const materials::J2Plasticity&>(*laws.law(c));
    EXPECT_DOUBLE_EQ(j2.hardening().yield_stress(), laws.yield_stress(c));
  }
  EXPECT_EQ(laws.law(2)->name(), "linear_elastic");
  EXPECT_EQ(laws.law(2)->youngs_modulus(), 3e9);
  EXPECT_EQ(laws.law(2)->poisson_ratio(), 0.35);
  EXPECT_EQ(laws.yield_stress(2), 0.0);
  // A law without a yield relation cannot drive the J2 kind.
  o.yield_law = "morgan2003_vertebra";
  EXPECT_THROW(CtCellLaws(model, o), InvalidInput);
}

// Density-mapped moduli reach the FE model: a bar of two densities in series (lower half
// 200, upper half 500 mg/cm^3) compressed axially has K = A / (L1/E1 + L2/E2). With nu = 0
// the uniaxial-strain field is piecewise linear along z and the interface is a cell face, so
// the trilinear FE solution is exact: only the solver tolerance (1e-10) separates them. A
// model using one modulus for all cells misses by tens of percent.
TEST(CtCellLaws, TwoDensityBarInSeriesHasTheSeriesStiffness) {
  CtVolume v;
  v.size = {{3, 2, 8}};
  v.spacing = {{1e-3, 1.5e-3, 0.5e-3}};
  v.origin = {{0.5e-3, 0.75e-3, 0.25e-3}}; // voxel corners from 0: the mesh spans [0, L] in z
  v.values.resize(v.n_voxels());
  for (unsigned int k = 0; k < v.size[2]; ++k)
    for (unsigned int j = 0; j < v.size[1]; ++j)
      for (unsigned int i = 0; i < v.size[0]; ++i)
        v.values[v.linear_index(i, j, k)] = k < 4 ? 200.0 : 500.0;
  const std::string file = scratch("two_density_bar.mha");
  write_ct_volume(v, file);
  CtParameters p;
  p.image_file = file;
  p.density_threshold = 0.1;
  p.density_modulus_law = "morgan2003_vertebra";
  p.poisson_ratio = 0.0;
  parallel::distributed::Triangulation<3> tria(MPI_COMM_WORLD);
  const CtModel model = build_ct_model(p, tria);
  ASSERT_EQ(model.cell_modulus.size(), 3u * 2 * 8);
  tria.refine_global(1); // children keep their coarse cell's law

  MechanicsSolver<3>::Parameters mp;
  mp.linear_tolerance = 1e-12;
  MechanicsSolver<3> solver(tria, mp);
  solver.set_cell_laws(CtCellLaws(model, {}).function());
  const double L = 8 * 0.5e-3, delta = 1e-6, A = 3e-3 * 3e-3;
  solver.boundary_conditions().add_dirichlet(4, "x,y,z", "0; 0; 0");
  solver.boundary_conditions().add_dirichlet(5, "x,y,z", "0; 0; -1e-6*t");
  solver.setup();
  solver.solve_quasi_static(1.0);
  const DensityModulusLaw law("morgan2003_vertebra", 0, 1e-3, 1e6);
  const double E1 = law.modulus(0.2), E2 = law.modulus(0.5);
  const double K = -solver.reaction_force(5)[2] / delta;
  const double K_series = A / (0.5 * L / E1 + 0.5 * L / E2);
  EXPECT_NEAR(K, K_series, 1e-8 * K_series);
  // The cell laws are what the solver uses, cell by cell.
  for (const auto& cell : solver.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned()) {
      EXPECT_EQ(solver.cell_material(cell).youngs_modulus(), cell->center()[2] < 0.5 * L ? E1 : E2);
    }
}

// Top centre frame = voxel: an index and an index-space direction map through the spacing and
// the direction matrix, x = origin + D diag(s) i (ct_volume.h), on an anisotropic rotated grid.
// The box placed by voxel and the box placed by the same point in mm must agree to round-off,
// and both read the voxel at that index.
TEST(CtBox, VoxelFrameMapsThroughSpacingAndDirection) {
  const std::string file = scratch("cylinder_frame.mha");
  write_ct_volume(cylinder_volume(), file);
  const CtVolume v = read_ct_volume(file); // the grid as the box will read it
  const std::array<double, 3> index{{7, 6, 11}}, axis{{1, 1, 1}};
  dealii::Point<3> centre;
  dealii::Tensor<1, 3> z;
  for (unsigned int r = 0; r < 3; ++r) {
    centre[r] = v.origin[r];
    for (unsigned int c = 0; c < 3; ++c) {
      centre[r] += v.direction[r][c] * v.spacing[c] * index[c];
      z[r] += v.direction[r][c] * v.spacing[c] * axis[c];
    }
  }
  z /= z.norm();
  auto box_from = [&](const std::string& frame, const std::string& top, const std::string& ax) {
    dealii::ParameterHandler prm;
    CtBoxParameters::declare(prm, "the test block");
    prm.set("Image file", file);
    prm.set("Top centre frame", frame);
    prm.set("Top centre", top);
    prm.set("Block z axis", ax);
    CtBoxParameters p;
    p.parse(prm, "CT/", [](const std::string& f) { return f; });
    return CtBox(p);
  };
  const CtBox by_voxel = box_from("voxel", "7, 6, 11", "1, 1, 1");
  std::ostringstream mm, direction;
  mm.precision(17);
  direction.precision(17);
  mm << 1e3 * centre[0] << ", " << 1e3 * centre[1] << ", " << 1e3 * centre[2];
  direction << z[0] << ", " << z[1] << ", " << z[2];
  const CtBox by_mm = box_from("physical", mm.str(), direction.str());
  for (unsigned int r = 0; r < 3; ++r) {
    // 1e-15 m: the two paths differ by the round-off of a few products of mm-sized numbers.
    EXPECT_NEAR(by_voxel.parameters().top_centre[r], centre[r], 1e-15) << r;
    // By mm through 17 significant digits: the same point to 1e-15 m.
    EXPECT_NEAR(by_voxel.parameters().top_centre[r], by_mm.parameters().top_centre[r], 1e-15) << r;
    for (unsigned int c = 0; c < 3; ++c)
      EXPECT_NEAR(by_voxel.parameters().axes[r][c], by_mm.parameters().axes[r][c], 1e-14)
          << r << "," << c;
  }
  // The block's origin reads voxel (7, 6, 11): value 800 + 0.001 (7 + 16 * 6 + 224 * 11) mg/cm^3.
  const double expected = 1e-3 * (800.0 + 0.001 * (7 + 16 * 6 + 224 * 11));
  EXPECT_NEAR(by_voxel.density(dealii::Point<3>()), expected, 1e-12);
  EXPECT_NEAR(by_mm.density(dealii::Point<3>()), expected, 1e-12);
  const std::string description = by_voxel.frame_description();
  EXPECT_NE(description.find("voxel (7, 6, 11)"), std::string::npos) << description;
  std::filesystem::remove(file);
}
