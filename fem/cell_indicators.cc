#include "fem/cell_indicators.h"

#include "base/exceptions.h"

#include <deal.II/base/geometry_info.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_values.h>

#include <algorithm>
#include <limits>

namespace spinesim::fem {

using namespace dealii;

void CellIndicatorsParameters::declare(ParameterHandler& prm) {
  prm.declare_entry("Critical principal strain", "0.02", Patterns::Double(0),
                    "Maximum principal strain at which a cell counts as failed [-].");
  prm.declare_entry("Critical principal stress", "100e6", Patterns::Double(0),
                    "Maximum principal stress at which a cell counts as failed [Pa].");
  prm.declare_entry("CFL safety factor", "0.5", Patterns::Double(0, 1),
                    "Fraction of the CFL limit reported as the cell's stable step [-].");
}

void CellIndicatorsParameters::parse(const ParameterHandler& prm) {
  critical_principal_strain = prm.get_double("Critical principal strain");
  critical_principal_stress = prm.get_double("Critical principal stress");
  cfl_safety_factor = prm.get_double("CFL safety factor");
  if (!(critical_principal_strain > 0))
    throw InvalidInput("Critical principal strain", "must be positive", "a strain > 0 [-]");
  if (!(critical_principal_stress > 0))
    throw InvalidInput("Critical principal stress", "must be positive", "a stress > 0 [Pa]");
  if (!(cfl_safety_factor > 0))
    throw InvalidInput("CFL safety factor", "must be positive", "a value in (0, 1]");
}

template <int dim>
void CellIndicators<dim>::compute(const MechanicsSolver<dim>& solver, bool with_state) {
  compute(solver, with_state, {}, true);
}

template <int dim>
void CellIndicators<dim>::compute(const MechanicsSolver<dim>& solver, bool with_state,
                                  const std::vector<bool>& cells, bool geometry) {
  const auto& dof_handler = solver.dof_handler();
  const unsigned int n_cells = dof_handler.get_triangulation().n_active_cells();
  for (auto* v : {&min_jacobian_ratio, &inverted, &aspect_ratio, &equivalent_plastic_strain,
                  &max_principal_strain, &max_principal_stress, &damage, &stable_time_step})
    v->reinit(n_cells);

  using CellIterator = typename DoFHandler<dim>::active_cell_iterator;
  std::vector<CellIterator> selected;
  for (const auto& cell : dof_handler.active_cell_iterators())
    if (cell->is_locally_owned() && (cells.empty() || cells[cell->active_cell_index()]))
      selected.push_back(cell);
  const long n = static_cast<long>(selected.size());
  const auto& u = solver.displacement();
  const unsigned int degree = solver.fe().degree;
  unsigned int n_inv = 0, n_dam = 0;
  if (with_state)
    solver.refresh_states(); // not from the threads
    // Cells are independent (each writes its own entries): the threads share them.
#pragma omp parallel if (n > 256) reduction(+ : n_inv, n_dam)
  {
    // Vertices (QTrapezoid points are in deal.II's lexicographic vertex order) and Gauss points.
    const QTrapezoid<dim> vertex_quadrature;
    const FEValuesExtractors::Vector displacements(0);
    FEValues<dim> at_vertices(solver.mapping(), solver.fe(), vertex_quadrature,
                              update_values | update_gradients | update_jacobians |
                                  update_quadrature_points);
    FEValues<dim> at_gauss(solver.mapping(), solver.fe(), solver.quadrature(),
                           geometry ? update_gradients | update_jacobians : update_gradients);
    std::vector<Tensor<2, dim>> grad_v(vertex_quadrature.size()),
        grad_q(solver.quadrature().size());
    std::vector<Tensor<1, dim>> u_v(vertex_quadrature.size());
    std::vector<double> local;
#pragma omp for schedule(dynamic, 64)
    for (long k = 0; k < n; ++k) {
      const auto& cell = selected[k];
      const unsigned int c = cell->active_cell_index();
      solver.get_cell_values(u, cell, local);
      at_gauss.reinit(cell);
      at_gauss[displacements].get_function_gradients_from_local_dof_values(local, grad_q);
      if (geometry) {
        at_vertices.reinit(cell);
        at_vertices[displacements].get_function_gradients_from_local_dof_values(local, grad_v);
        at_vertices[displacements].get_function_values_from_local_dof_values(local, u_v);

        double jmin = std::numeric_limits<double>::max(), jmax = -jmin;
        auto take = [&](const DerivativeForm<1, dim, dim>& J, const Tensor<2, dim>& H) {
          const double det =
              determinant(Tensor<2, dim>(J)) * determinant(unit_symmetric_tensor<dim>() + H);
          jmin = std::min(jmin, det);
          jmax = std::max(jmax, det);
        };
        for (unsigned int q = 0; q < vertex_quadrature.size(); ++q)
          take(at_vertices.jacobian(q), grad_v[q]);
        for (unsigned int q = 0; q < solver.quadrature().size(); ++q)
          take(at_gauss.jacobian(q), grad_q[q]);
        min_jacobian_ratio(c) = jmax > 0 ? jmin / jmax : jmin;
        inverted(c) = jmin <= 0 ? 1 : 0;
        n_inv += jmin <= 0;

        double emin = std::numeric_limits<double>::max(), emax = 0;
        for (unsigned int l = 0; l < GeometryInfo<dim>::lines_per_cell; ++l) {
          const unsigned int a = GeometryInfo<dim>::line_to_cell_vertices(l, 0),
                             b = GeometryInfo<dim>::line_to_cell_vertices(l, 1);
          const Point<dim> xa = at_vertices.quadrature_point(a) + u_v[a],
                           xb = at_vertices.quadrature_point(b) + u_v[b];
          const double len = xa.distance(xb);
          emin = std::min(emin, len);
          emax = std::max(emax, len);
        }
        aspect_ratio(c) = emin > 0 ? emax / emin : std::numeric_limits<float>::max();
        const double wave = solver.cell_material(cell).p_wave_speed();
        stable_time_step(c) = prm_.cfl_safety_factor * emin / (degree * wave);
      }

      double ep = 0, e1 = -std::numeric_limits<double>::max(), s1 = e1;
      if (with_state) {
        const auto data = solver.quadrature_point_data(cell);
        for (const auto& d : data) {
          ep += d.state.equivalent_plastic_strain;
          e1 = std::max(e1, eigenvalues(d.strain)[0]);
          s1 = std::max(s1, eigenvalues(d.cauchy_stress)[0]);
        }
        ep /= data.size();
      } else {
        s1 = 0;
        for (const auto& H : grad_q)
          e1 = std::max(e1, eigenvalues(symmetrize(H))[0]);
      }
      equivalent_plastic_strain(c) = ep;
      max_principal_strain(c) = e1;
      max_principal_stress(c) = s1;
      damage(c) =
          std::max(e1 / prm_.critical_principal_strain, s1 / prm_.critical_principal_stress);
      n_dam += damage(c) >= 1.0;
    }
  }
  const MPI_Comm comm = solver.mpi_communicator();
  n_inverted_ = Utilities::MPI::sum(n_inv, comm);
  n_damaged_ = Utilities::MPI::sum(n_dam, comm);
}

template class CellIndicators<2>;
template class CellIndicators<3>;

} // namespace spinesim::fem
