#include "fem/ct/ct_parameters.h"

#include "base/exceptions.h"
#include "fem/ct/density_calibration.h"
#include "fem/ct/density_modulus_law.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace spinesim::fem {

void CtParameters::declare(dealii::ParameterHandler& prm) {
  declare_volume(prm);
  declare_material(prm);
}

void CtParameters::declare_volume(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry(
      "Image file", "", FileName(FileName::input),
      "CT volume: NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr), MetaImage (.mha, .mhd), or a "
      "directory holding one DICOM series (read through GDCM, Rescale Slope/Intercept "
      "applied: HU for CT); spacing read as mm and converted to m; relative to the scene file "
      "[-].");
  prm.declare_entry("Label file", "", FileName(FileName::input),
                    "Segmentation on the image grid (integer labels), needed when Labels is "
                    "not empty; relative to the scene file [-].");
  DensityCalibration::declare(prm);
  prm.declare_entry("Labels", "", List(Integer(0, 254)),
                    "Labels to mesh, comma separated; each becomes the material id of its "
                    "cells. Empty: threshold mode (material id 0) [-].");
  prm.declare_entry("Density threshold", "0.1", Double(),
                    "Threshold mode: voxels with calibrated density >= this are meshed [g/cm^3].");
  prm.declare_entry("Coarsening factor", "1", Integer(1, 32),
                    "Voxels per cell edge: a block of f^3 voxels becomes one hexahedron [-].");
  prm.declare_entry("Block rule", "majority", Selection("majority|any"),
                    "A block becomes a cell when at least half (majority) or one (any) of its "
                    "voxels is selected; cell density = mean of its selected voxels [-].");
  prm.declare_entry("Keep largest component", "true", Bool(),
                    "Keep only the largest face-connected set of cells (drops loose voxels) [-].");
  prm.declare_entry("Mark end faces", "true", Bool(),
                    "Give outer faces on the lowest z plane boundary id 4 and on the highest "
                    "z plane id 5 (others 0), e.g. lower cap fixed, upper cap displaced [-].");
  prm.declare_entry(
      "End face labels", "", List(Integer(0, 254), 0, 2),
      "Empty: end faces are the lowest / highest z faces of the whole mesh. Two "
      "labels 'lower, upper' (e.g. the PMMA caps 5, 6 of verse004): the lowest "
      "z faces of the lower label's cells get id 4, the highest of the upper's 5 [-].");
  prm.declare_entry("Label moduli", "", Map(Integer(0, 254), Double(0)),
                    "Young's modulus per label replacing the density law, 'label: E' comma "
                    "list, e.g. '5: 2.5e9, 6: 2.5e9' for PMMA caps that carry no density [Pa].");
  prm.declare_entry("Label densities", "", Map(Integer(0, 254), Double(0)),
                    "Density per label replacing the image's, 'label: rho' comma list, e.g. "
                    "'5: 1.18, 6: 1.18' for PMMA [g/cm^3].");
}

void CtParameters::declare_material(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Density modulus law", "morgan2003_vertebra",
                    Selection(DensityModulusLaw::names()),
                    "Density-elasticity relation, rho in g/cm^3: morgan2003_vertebra "
                    "E = 4730 rho^1.56 MPa; kopperdahl2002 E = 2980 rho^1.05 MPa; crawford2003 "
                    "E = -34.7 + 3230 rho MPa; constant E = Constant modulus [-].");
  prm.declare_entry("Constant modulus", "1e9", Double(0),
                    "Young's modulus of the 'constant' law [Pa].");
  prm.declare_entry("Minimum density", "0.001", Double(0),
                    "Densities below this are raised to it before the law [g/cm^3].");
  prm.declare_entry("Minimum modulus", "1e6", Double(0),
                    "Moduli below this are raised to it (keeps the stiffness positive) [Pa].");
  prm.declare_entry("Poisson ratio", "0.3", Double(-1, 0.5),
                    "Poisson's ratio of the bone cells [-].");
}

std::string CtParameters::resolve_path(const std::string& file, const std::string& base) {
  if (file.empty() || base.empty())
    return file;
  const std::filesystem::path p(file);
  if (p.is_absolute())
    return file;
  return (std::filesystem::path(base) / p).lexically_normal().string();
}

void CtParameters::parse(const dealii::ParameterHandler& prm, const std::string& base) {
  parse_volume(prm, base);
  parse_material(prm);
}

void CtParameters::parse_volume(const dealii::ParameterHandler& prm, const std::string& base) {
  image_file = resolve_path(prm.get("Image file"), base);
  label_file = resolve_path(prm.get("Label file"), base);
  value_type = prm.get("Value type");
  calibration_intercept = prm.get_double("Calibration intercept");
  calibration_slope = prm.get_double("Calibration slope");
  labels.clear();
  for (const auto& s : dealii::Utilities::split_string_list(prm.get("Labels"), ','))
    labels.push_back(dealii::Utilities::string_to_int(s));
  density_threshold = prm.get_double("Density threshold");
  coarsening_factor = static_cast<unsigned int>(prm.get_integer("Coarsening factor"));
  block_rule = prm.get("Block rule");
  keep_largest_component = prm.get_bool("Keep largest component");
  mark_end_faces = prm.get_bool("Mark end faces");
  end_face_labels.clear();
  for (const auto& s : dealii::Utilities::split_string_list(prm.get("End face labels"), ','))
    end_face_labels.push_back(dealii::Utilities::string_to_int(s));
  if (end_face_labels.size() == 1)
    throw InvalidInput("End face labels", "one label given",
                       "empty, or two labels 'lower cap, upper cap'");
  for (int l : end_face_labels)
    if (std::find(labels.begin(), labels.end(), l) == labels.end())
      throw InvalidInput("End face labels", "label " + std::to_string(l) + " is not meshed",
                         "labels listed in Labels");
  auto parse_map = [&](const std::string& entry, double floor, const std::string& unit) {
    std::map<int, double> out;
    for (const auto& item : dealii::Utilities::split_string_list(prm.get(entry), ',')) {
      const auto kv = dealii::Utilities::split_string_list(item, ':');
      const double v = dealii::Utilities::string_to_double(kv.at(1));
      if (!(v > floor))
        throw InvalidInput(entry, "value " + kv.at(1) + " for label " + kv.at(0),
                           "positive values " + unit);
      out[dealii::Utilities::string_to_int(kv.at(0))] = v;
    }
    return out;
  };
  label_moduli = parse_map("Label moduli", 0, "[Pa]");
  label_densities = parse_map("Label densities", 0, "[g/cm^3]");

  if (image_file.empty())
    throw InvalidInput("Image file", "no CT image given",
                       "a .nii, .nii.gz, .nrrd, .nhdr, .mha or .mhd file");
  if (!labels.empty() && label_file.empty())
    throw InvalidInput("Label file", "Labels are given but no label file",
                       "a segmentation file, or an empty Labels list for threshold mode");
  // Constructing it validates value type and calibration.
  if (value_type == "hu")
    DensityCalibration(DensityCalibration::ValueType::hu, calibration_intercept, calibration_slope);
}

void CtParameters::parse_material(const dealii::ParameterHandler& prm) {
  density_modulus_law = prm.get("Density modulus law");
  constant_modulus = prm.get_double("Constant modulus");
  minimum_density = prm.get_double("Minimum density");
  minimum_modulus = prm.get_double("Minimum modulus");
  poisson_ratio = prm.get_double("Poisson ratio");
  // Constructing it validates law and floors.
  DensityModulusLaw(density_modulus_law, constant_modulus, minimum_density, minimum_modulus);
  if (!(poisson_ratio > -1 && poisson_ratio < 0.5))
    throw InvalidInput("Poisson ratio", std::to_string(poisson_ratio), "a value in (-1, 0.5)");
}

} // namespace spinesim::fem
