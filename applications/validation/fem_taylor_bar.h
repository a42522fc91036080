#ifndef SPINESIM_APPLICATIONS_VALIDATION_FEM_TAYLOR_BAR_H
#define SPINESIM_APPLICATIONS_VALIDATION_FEM_TAYLOR_BAR_H

// The Taylor bar in FEM: the copper cylinder of the taylor_bar scenario as a deal.II mesh
// (GridGenerator::subdivided_cylinder turned onto the z axis, the hull on a cylindrical
// manifold, refined globally with p4est), total-Lagrangian finite strain with the scene's
// law (j2_finite_strain) and F-bar against the volumetric locking of isochoric plastic flow,
// explicit central differences with the lumped mass at the CFL step of the CURRENT cells (they
// shorten several times at the impact face). The rigid frictionless wall is the impact face
// held at z = 0 (u_z = 0, sliding free): the face meets the wall at t = 0 and stays on it for
// the 80 us of the benchmark. Figures as the SPG run's: final length, impact-face radius (the
// mean over the rim's nodes, and their largest), the energy balance (the supports absorb the
// momentum of the face's nodes at t = 0), plastic work.

#include "applications/framework/run_context.h"
#include "applications/validation/taylor_bar_parameters.h"
#include "fem/materials/constitutive_law.h"
#include "fem/mechanics_parameters.h"

#include <memory>

namespace spinesim::applications {

void run_fem_taylor_bar(framework::RunContext& ctx,
                        std::shared_ptr<const materials::ConstitutiveLaw> law,
                        const TaylorParameters& bar, const fem::MechanicsParameters<3>& mechanics);

} // namespace spinesim::applications

#endif
