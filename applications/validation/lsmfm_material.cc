#include "applications/validation/lsmfm_material.h"

#include "base/exceptions.h"

#include <limits>
#include <sstream>

namespace spinesim::applications {

template <int dim>
typename meshfree::LsmfmSolver<dim>::Material lsmfm_material(const materials::LawParameters& law,
                                                             const std::string& models,
                                                             const std::string& run) {
  if (("|" + models + "|").find("|" + law.model + "|") == std::string::npos) {
    std::ostringstream allowed;
    std::stringstream list(models);
    for (std::string m; std::getline(list, m, '|');)
      allowed << (allowed.tellp() > 0 ? ", " : "") << m;
    throw InvalidInput("Material/Model", "'" + law.model + "' for " + run,
                       allowed.str() + " (the LSMFM has its own J2 flow rule with linear "
                                       "hardening, Kwon & Youn eqs. 12-14)");
  }
  if (law.model != "linear_elastic" && law.saturation_stress > 0)
    throw InvalidInput("Material/Saturation stress", "> 0 with the LSMFM",
                       "0: the LSMFM's hardening is linear (Kwon & Youn eq. 12c)");
  typename meshfree::LsmfmSolver<dim>::Material mat;
  mat.youngs_modulus = law.youngs_modulus;
  mat.poisson_ratio = law.poisson_ratio;
  mat.yield_stress =
      law.model == "linear_elastic" ? std::numeric_limits<double>::infinity() : law.yield_stress;
  mat.hardening_modulus = law.hardening_modulus;
  return mat;
}

void require_one_lsmfm_rank(unsigned int n_ranks) {
  if (n_ranks != 1)
    throw InvalidInput("MPI ranks", std::to_string(n_ranks),
                       "1: the LSMFM solver runs on one rank (its matrix is a serial sparse "
                       "Cholesky factorisation)");
}

template meshfree::LsmfmSolver<2>::Material
lsmfm_material<2>(const materials::LawParameters&, const std::string&, const std::string&);
template meshfree::LsmfmSolver<3>::Material
lsmfm_material<3>(const materials::LawParameters&, const std::string&, const std::string&);

} // namespace spinesim::applications
