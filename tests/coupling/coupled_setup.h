#ifndef SPINESIM_TESTS_COUPLING_COUPLED_SETUP_H
#define SPINESIM_TESTS_COUPLING_COUPLED_SETUP_H

// The small coupled model the coupling's unit tests share (checkpoint, snapshot, materials).

#include "coupling/fem_particle_coupling.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "meshfree/particle_method.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/distributed/tria.h>

#include <memory>
#include <string>
#include <vector>

namespace spinesim::coupling::testing_setup {

// A unit square (cube) of 8 x 8 (4 x 4 x 4) explicit Q1 cells with a particle block in
// [0.25, 0.75]^dim: linear elastic with nu = 0.25 (bond-based PD's in 3-D and plane strain), or
// J2 yielding at a strain of 6e-5 with `plastic` (the fields the tests impose are plastic).
template <int dim>
struct CoupledSetup {
  // second_youngs > 0: the cells right of x = 0.5 are material 1, that law with this E.
  CoupledSetup(const std::string& method, bool plastic, double second_youngs = 0)
      : tria(MPI_COMM_WORLD) {
    fem::MeshParameters mesh;
    mesh.origin = {0, 0, 0};
    mesh.lengths = {1, 1, 1};
    mesh.subdivisions = {dim == 2 ? 8u : 4u, dim == 2 ? 8u : 4u, 4u};
    fem::build_mesh(mesh, tria);
    if (second_youngs > 0)
      for (const auto& cell : tria.active_cell_iterators())
        if (cell->center()[0] > 0.5)
          cell->set_material_id(1);
    typename fem::MechanicsSolver<dim>::Parameters mech;
    mech.time_integration = "explicit";
    solver = std::make_unique<fem::MechanicsSolver<dim>>(tria, mech);
    materials::LawParameters law;
    law.poisson_ratio = 0.25;
    if (plastic) {
      law.model = "j2_plasticity";
      law.yield_stress = 1e6;
      law.hardening_modulus = 1e8;
    }
    solver->set_material(0, materials::create_law(law));
    if (second_youngs > 0) {
      law.youngs_modulus = second_youngs;
      solver->set_material(1, materials::create_law(law));
    }
    solver->setup();
    dealii::ParameterHandler prm;
    meshfree::declare_particle_method_sections(prm);
    prm.enter_subsection("Bond based");
    prm.set("Plane model", "plane_strain"); // the FEM's
    prm.leave_subsection();
    prm.enter_subsection("NOSB");
    prm.set("Horizon ratio", "2.015"); // small families keep the 3-D case quick
    prm.leave_subsection();
    parameters.particles_method = method;
    parameters.make_method = meshfree::particle_method_maker<dim>(method, prm, "test");
    parameters.region_lower = std::vector<double>(dim, 0.25);
    parameters.region_upper = std::vector<double>(dim, 0.75);
  }
  dealii::parallel::distributed::Triangulation<dim> tria;
  std::unique_ptr<fem::MechanicsSolver<dim>> solver;
  typename FemParticleCoupling<dim>::Parameters parameters;
};

} // namespace spinesim::coupling::testing_setup

#endif
