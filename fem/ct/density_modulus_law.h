#ifndef SPINESIM_FEM_CT_DENSITY_MODULUS_LAW_H
#define SPINESIM_FEM_CT_DENSITY_MODULUS_LAW_H

// Published density-elasticity relations for bone, rho in g/cm^3 -> E. The formulas give MPa;
// this API returns Pa (SI, what the mechanics uses).
//   morgan2003_vertebra  E = 4730 rho^1.56 MPa  (Morgan et al., J Biomech 2003, vertebral
//                        trabecular bone, apparent density)
//   kopperdahl2002       E = 2980 rho^1.05 MPa, compressive yield 37.4 rho^1.39 MPa
//                        (Kopperdahl, Morgan, Keaveny, J Orthop Res 2002, QCT density)
//   crawford2003         E = -34.7 + 3230 rho MPa  (Crawford, Cann, Keaveny, Bone 2003,
//                        QCT density)
//   constant             E = the given modulus, independent of rho
// rho must be the density the relation was fitted with (apparent vs. QCT-equivalent); the
// calibration is the user's choice. Floors: rho below `minimum density` is raised to it before
// the formula (power laws are undefined for rho < 0), and E below `minimum modulus` is raised
// to it (e.g. crawford2003 is negative for rho < 0.0107 g/cm^3).

#include <string>
#include <vector>

namespace spinesim::fem {

class DensityModulusLaw {
 public:
  // InvalidInput for an unknown name or a non-positive floor / constant modulus.
  DensityModulusLaw(const std::string& name, double constant_modulus, double minimum_density,
                    double minimum_modulus);

  static std::string names() { return "morgan2003_vertebra|kopperdahl2002|crawford2003|constant"; }

  // [Pa] the published formula at rho [g/cm^3], no floors (may be negative or NaN for rho < 0).
  double raw_modulus(double rho) const;
  // [Pa] with both floors applied.
  double modulus(double rho) const;
  // Whether the law defines a yield stress (kopperdahl2002 only).
  bool has_yield_stress() const { return name_ == "kopperdahl2002"; }
  // [Pa] compressive yield stress at max(rho, minimum density); InvalidInput if undefined.
  double yield_stress(double rho) const;

  struct Evaluation {
    std::vector<double> modulus;      // [Pa], floors applied
    unsigned int floored_density = 0; // cells whose density was raised to the minimum
    unsigned int floored_modulus = 0; // cells whose modulus was raised to the minimum
    unsigned int floored_cells = 0;   // cells where either floor acted
  };
  // One modulus per entry of `densities` [g/cm^3], with the floor counts for the report.
  Evaluation evaluate(const std::vector<double>& densities) const;

  const std::string& name() const { return name_; }
  double minimum_density() const { return minimum_density_; } // [g/cm^3]
  double minimum_modulus() const { return minimum_modulus_; } // [Pa]

 private:
  std::string name_;
  double constant_modulus_;
  double minimum_density_;
  double minimum_modulus_;
};

} // namespace spinesim::fem

#endif
