#ifndef SPINESIM_APPLICATIONS_VALIDATION_LSMFM_MATERIAL_H
#define SPINESIM_APPLICATIONS_VALIDATION_LSMFM_MATERIAL_H

// What the LSMFM scenarios share about their set-up: the solver's material from a scene's
// Material section (the LSMFM has its own J2 flow rule with linear hardening, Kwon & Youn
// 2005, eqs. 12-14) and its one-rank limit.

#include "fem/materials/law_parameters.h"
#include "meshfree/lsmfm/lsmfm_solver.h"

#include <string>

namespace spinesim::applications {

// The material of `law`, which must be one of `models` ('|'-separated: linear_elastic,
// j2_plasticity, j2_finite_strain) without saturation; linear_elastic gives an infinite yield
// stress. InvalidInput naming the entry otherwise; `run` names the run in the message.
template <int dim>
typename meshfree::LsmfmSolver<dim>::Material lsmfm_material(const materials::LawParameters& law,
                                                             const std::string& models,
                                                             const std::string& run);

// The LSMFM's matrix is a serial sparse Cholesky factorisation: InvalidInput unless one rank.
void require_one_lsmfm_rank(unsigned int n_ranks);

} // namespace spinesim::applications

#endif
