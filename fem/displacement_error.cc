#include "fem/displacement_error.h"

#include "fem/mechanics_solver.h"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/vector.h>

#include <algorithm>

namespace spinesim::fem {

template <int dim>
ErrorSums displacement_error_sums(const MechanicsSolver<dim>& solver,
                                  const dealii::Function<dim>& exact) {
  const auto& fe = solver.fe();
  const dealii::QGauss<dim> quadrature(fe.degree + 2);
  dealii::FEValues<dim> fe_values(solver.mapping(), fe, quadrature,
                                  dealii::update_values | dealii::update_quadrature_points |
                                      dealii::update_JxW_values);
  std::vector<double> dof_values(fe.n_dofs_per_cell());
  dealii::Vector<double> u_exact(dim);
  ErrorSums sums;
  for (const auto& cell : solver.dof_handler().active_cell_iterators()) {
    if (!cell->is_locally_owned() || !solver.is_active(cell))
      continue;
    fe_values.reinit(cell);
    solver.get_cell_values(solver.displacement(), cell, dof_values);
    for (unsigned int q = 0; q < quadrature.size(); ++q) {
      exact.vector_value(fe_values.quadrature_point(q), u_exact);
      double e2 = 0, u2 = 0;
      for (unsigned int c = 0; c < dim; ++c) {
        double u_h = 0;
        for (unsigned int i = 0; i < fe.n_dofs_per_cell(); ++i)
          if (fe.system_to_component_index(i).first == c)
            u_h += dof_values[i] * fe_values.shape_value(i, q);
        e2 += (u_h - u_exact[c]) * (u_h - u_exact[c]);
        u2 += u_exact[c] * u_exact[c];
      }
      sums.error_squared += e2 * fe_values.JxW(q);
      sums.reference_squared += u2 * fe_values.JxW(q);
    }
  }
  return sums;
}

template <int dim>
double max_cell_diameter(const MechanicsSolver<dim>& solver) {
  double h = 0;
  for (const auto& cell : solver.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned() && solver.is_active(cell))
      h = std::max(h, cell->diameter());
  return h;
}

template ErrorSums displacement_error_sums(const MechanicsSolver<2>&, const dealii::Function<2>&);
template ErrorSums displacement_error_sums(const MechanicsSolver<3>&, const dealii::Function<3>&);
template double max_cell_diameter(const MechanicsSolver<2>&);
template double max_cell_diameter(const MechanicsSolver<3>&);

} // namespace spinesim::fem
