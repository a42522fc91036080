#ifndef SPINESIM_FEM_CT_CT_PARAMETERS_H
#define SPINESIM_FEM_CT_CT_PARAMETERS_H

// Input-file entries of a CT-based model, declared in the CURRENT subsection. Relative file
// names are resolved against the directory of the scene file (parse's base_directory).

#include <deal.II/base/parameter_handler.h>

#include <map>
#include <string>
#include <vector>

namespace spinesim::fem {

struct CtParameters {
  std::string image_file;              // density or HU volume
  std::string label_file;              // segmentation on the same grid (label mode)
  std::string value_type = "density";  // density (mg/cm^3) | hu
  double calibration_intercept = 0.0;  // [g/cm^3]     rho = a + b HU (hu only)
  double calibration_slope = 1e-3;     // [g/cm^3/HU]
  std::vector<int> labels;             // empty: threshold mode
  double density_threshold = 0.1;      // [g/cm^3] threshold mode
  unsigned int coarsening_factor = 1;  // voxels per cell edge
  std::string block_rule = "majority"; // majority | any
  bool keep_largest_component = true;
  bool mark_end_faces = true;       // z- faces id 4, z+ faces id 5
  std::vector<int> end_face_labels; // {lower cap, upper cap} labels; empty = whole mesh
  std::string density_modulus_law = "morgan2003_vertebra";
  double constant_modulus = 1e9;         // [Pa] law "constant"
  double minimum_density = 1e-3;         // [g/cm^3] floor before the law
  double minimum_modulus = 1e6;          // [Pa] floor after the law
  double poisson_ratio = 0.3;            // [-]
  std::map<int, double> label_moduli;    // [Pa] label -> E replacing the law (PMMA caps)
  std::map<int, double> label_densities; // [g/cm^3] label -> density replacing the image's

  // All entries in the current subsection: declare_volume() + declare_material().
  static void declare(dealii::ParameterHandler& prm);
  // Reads and validates (InvalidInput naming the parameter); relative paths are made absolute
  // against base_directory (the scene file's directory; empty = leave them as given).
  void parse(const dealii::ParameterHandler& prm, const std::string& base_directory = "");

  // The two halves, for scenes that keep the image and the bone law in different sections
  // (vertebra_compression: "CT" and "Bone").
  // Volume: files, calibration, selection, coarsening, end faces, label moduli / densities.
  static void declare_volume(dealii::ParameterHandler& prm);
  void parse_volume(const dealii::ParameterHandler& prm, const std::string& base_directory = "");
  // Material: Density modulus law, Constant modulus, Minimum density / modulus, Poisson ratio.
  static void declare_material(dealii::ParameterHandler& prm);
  void parse_material(const dealii::ParameterHandler& prm);

  // `file` unchanged if empty or absolute, else base_directory/file.
  static std::string resolve_path(const std::string& file, const std::string& base_directory);
};

} // namespace spinesim::fem

#endif
