// FemParticleCoupling::step_spectrum: the stability of the explicit coupled step, measured.
//
// Central differences advance a linear system M ü = −K u by a linear map G of (u^n, v^{n−½}).
// For a symmetric K below the CFL step every eigenvalue of G has |μ| = 1 (a conserved shadow
// energy); the FEM/particle splice makes the coupled K non-symmetric, and eigenvalues with
// |μ| > 1 are modes that grow by |μ| per step. G is probed column by column: one step from the
// current state with one unknown perturbed, less one unperturbed step from the same state and
// time (so loads and Dirichlet values cancel).

#include "coupling/fem_particle_coupling.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>
#include <deal.II/lac/lapack_full_matrix.h>

#include <string>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
std::vector<std::complex<double>>
FemParticleCoupling<dim>::step_spectrum(double dt, unsigned int max_unknowns) {
  auto& solver = state_.fem;
  auto& particles = state_.particles;
  if (Utilities::MPI::n_mpi_processes(solver.mpi_communicator()) != 1)
    throw InvalidInput("MPI ranks", "the step spectrum probes every unknown on one rank", "1");
  std::vector<unsigned int> free_particles;
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i])
      free_particles.push_back(i);
  const unsigned int n_fem = solver.dof_handler().n_dofs();
  const unsigned int n = n_fem + dim * free_particles.size(); // displacement unknowns
  if (n > max_unknowns)
    throw InvalidInput("unknowns of the step spectrum",
                       std::to_string(n) + " (FEM DoFs + particle components): the dense "
                                           "eigenvalue solve needs (2n)^2 doubles",
                       "at most " + std::to_string(max_unknowns) + ": a coarser scene");

  using VectorType = typename fem::MechanicsSolver<dim>::VectorType;
  const VectorType u0 = solver.displacement(), v0 = solver.velocity(); // ghosted copies
  std::vector<Tensor<1, dim>> pu0, pv0;
  for (const unsigned int i : free_particles) {
    pu0.push_back(particles.displacement(i));
    pv0.push_back(particles.velocity(i));
  }
  const double t0 = integrator_.time(), fem_t0 = solver.time();
  // The map of a step at a constant dt: every probe advances its velocities over dt, whatever
  // step came before (restored at the end).
  const double previous_step = solver.previous_step();
  // Perturbations small against any breaking stretch or yield strain; the map is linear in them.
  const double du = 1e-8 * state_.spacing, dv = du / dt;

  // Sets (u, v) = state + perturbation of entry `k` of the 2n-vector (k < 0: none; −2: the
  // state as it was, with its last step).
  VectorType u(solver.lumped_mass()), v(solver.lumped_mass());
  const auto set_state = [&](int k) {
    for (unsigned int j = 0; j < n_fem; ++j) {
      u(j) = u0(j) + (k == static_cast<int>(j) ? du : 0.0);
      v(j) = v0(j) + (k == static_cast<int>(n + j) ? dv : 0.0);
    }
    u.compress(VectorOperation::insert);
    v.compress(VectorOperation::insert);
    solver.set_state(u, v);
    solver.set_time(fem_t0);
    solver.set_previous_step(k == -2 ? previous_step : dt);
    for (unsigned int p = 0; p < free_particles.size(); ++p) {
      particles.displacement(free_particles[p]) = pu0[p];
      particles.velocity(free_particles[p]) = pv0[p];
      for (unsigned int d = 0; d < dim; ++d) {
        const int slot = static_cast<int>(n_fem + dim * p + d);
        if (k == slot)
          particles.displacement(free_particles[p])[d] += du;
        if (k == static_cast<int>(n) + slot)
          particles.velocity(free_particles[p])[d] += dv;
      }
    }
    integrator_.set_time(t0);
    refresh(); // ghosts from the FEM, interface values from the particles
  };
  const auto read_state = [&](std::vector<double>& x) {
    const auto& uu = solver.displacement();
    const auto& vv = solver.velocity();
    for (unsigned int j = 0; j < n_fem; ++j) {
      x[j] = uu(j);
      x[n + j] = vv(j);
    }
    for (unsigned int p = 0; p < free_particles.size(); ++p)
      for (unsigned int d = 0; d < dim; ++d) {
        x[n_fem + dim * p + d] = particles.displacement(free_particles[p])[d];
        x[n + n_fem + dim * p + d] = particles.velocity(free_particles[p])[d];
      }
  };

  std::vector<double> base(2 * n), probe(2 * n);
  set_state(-1);
  step(dt);
  read_state(base);
  LAPACKFullMatrix<double> G(2 * n, 2 * n);
  for (unsigned int c = 0; c < 2 * n; ++c) {
    set_state(static_cast<int>(c));
    step(dt);
    read_state(probe);
    // The map of the scaled state (u / du, v / dv): a similarity transform of the map of
    // (u, v), with the same eigenvalues.
    for (unsigned int r = 0; r < 2 * n; ++r)
      G(r, c) = (probe[r] - base[r]) / (r < n ? du : dv);
  }
  set_state(-2); // the state as it was
  G.compute_eigenvalues();
  std::vector<std::complex<double>> mu(2 * n);
  for (unsigned int k = 0; k < 2 * n; ++k)
    mu[k] = G.eigenvalue(k);
  return mu;
}

template std::vector<std::complex<double>> FemParticleCoupling<2>::step_spectrum(double,
                                                                                 unsigned int);
template std::vector<std::complex<double>> FemParticleCoupling<3>::step_spectrum(double,
                                                                                 unsigned int);

} // namespace spinesim::coupling
