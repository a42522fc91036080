// Assembly of MechanicsSolver: internal and external forces and the consistent tangent over the
// active cells, with loads blended along the quasi-static load path.

#include "fem/mechanics_solver.h"

#include "base/collective_failure.h"
#include "base/exceptions.h"
#include "base/scoped_time.h"
#include "fem/f_bar.h"
#include "fem/mean_dilatation.h"

#include <deal.II/fe/fe_values.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>

namespace spinesim::fem {

namespace cavity_wall {
// Calls f(face values) for each (sub)face of `cell` that borders a cell `active` rejects:
// the whole face where the neighbour is as fine or coarser, each subface whose neighbour
// child is inactive where the neighbour is finer.
template <int dim, typename Cell, typename Active, typename F>
void for_each_face(const Cell& cell, const Active& active, FEFaceValues<dim>& face_values,
                   FESubfaceValues<dim>& subface_values, const F& f) {
  for (const unsigned int face : cell->face_indices()) {
    if (cell->face(face)->at_boundary())
      continue;
    if (cell->face(face)->has_children()) {
      for (unsigned int sf = 0; sf < cell->face(face)->n_children(); ++sf)
        if (!active(cell->neighbor_child_on_subface(face, sf))) {
          subface_values.reinit(cell, face, sf);
          f(static_cast<const FEFaceValuesBase<dim>&>(subface_values));
        }
    } else if (!active(cell->neighbor(face))) {
      face_values.reinit(cell, face);
      f(static_cast<const FEFaceValuesBase<dim>&>(face_values));
    }
  }
}
} // namespace cavity_wall

using namespace dealii;
using materials::Tensor2;

template <int dim>
double MechanicsSolver<dim>::load_blend(Function<dim>& f, const Point<dim>& x, unsigned int c,
                                        double load_factor) const {
  f.set_time(target_time_);
  double value = load_factor * f.value(x, c);
  if (loaded_ && load_factor < 1.0) {
    f.set_time(previous_time_);
    value += (1.0 - load_factor) * f.value(x, c);
  }
  return value;
}

template <int dim>
typename MechanicsSolver<dim>::AssemblyNorms
MechanicsSolver<dim>::assemble(bool with_matrix, double load_factor,
                               const AffineConstraints<double>& constraints) {
  ScopedTime timer(timings_.assembly);
  MatrixType& matrix = assemble_into_explicit_matrix_ ? explicit_matrix_ : matrix_;
  if (with_matrix && !assembly_cells_)
    matrix = 0;
  rhs_ = 0;
  VectorType f_int(owned_, comm_);
  external_force_.reinit(owned_, comm_); // kept for the energy account
  VectorType& f_ext = external_force_;

  const unsigned int nq = quadrature_.size(), n = fe_.n_dofs_per_cell();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_,
                          update_values | update_gradients | update_quadrature_points |
                              update_JxW_values);
  FEFaceValues<dim> fe_face(*mapping_, fe_, face_quadrature_,
                            update_values | update_quadrature_points | update_normal_vectors |
                                update_JxW_values);
  FESubfaceValues<dim> fe_subface(*mapping_, fe_, face_quadrature_,
                                  update_values | update_quadrature_points | update_normal_vectors |
                                      update_JxW_values);
  const FEValuesExtractors::Vector displacements(0);
  FullMatrix<double> cell_matrix(n, n);
  Vector<double> cell_rhs(n), cell_fint(n), cell_fext(n);
  std::vector<types::global_dof_index> dofs(n);
  std::vector<Tensor<2, dim>> grads(nq);
  std::vector<double> local_u(n);
  std::vector<unsigned int> comp(n);
  for (unsigned int i = 0; i < n; ++i)
    comp[i] = fe_.system_to_component_index(i).first;
  std::vector<std::array<double, dim * dim>> w(n); // w_i[d][L] = Σ_J ∇N_i,J A(c_i,J,d,L) JxW
  double A[3][3][3][3];
  // B-bar (mean_dilatation.h): H̄ at the points, δH̄_i = g_i ⊗ e_{c_i} + β_i I₃ in the force
  // and W_i = δH̄_i : A JxW (3×3, with zz in plane strain) in the tangent.
  const bool bbar = prm_.volumetric_locking == "bbar";
  MeanDilatation<dim> mean_dilatation;
  double average_dilatation = 0;
  std::vector<double> beta(n);
  std::vector<std::array<double, 9>> wb(bbar ? n : 0);
  // F-bar (f_bar.h): P̄ = P(F̄) at the points and its own force; no tangent.
  const bool fbar = prm_.volumetric_locking == "fbar";
  if (fbar && with_matrix)
    throw std::logic_error("F-bar has no consistent tangent: explicit steps only");
  FBar<dim> f_bar;
  std::vector<double> fbar_force(fbar ? n : 0);

  // A point that fails (inverted, non-finite), or anything else thrown in the loop, ends this
  // rank's loop; every rank then meets in raise_on_every_rank after the collective compresses
  // below.
  std::exception_ptr failure;
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (failure)
      break;
    try {
      if (!cell->is_locally_owned() ||
          !(assembly_cells_ ? (*assembly_cells_)[cell->active_cell_index()] : is_active(cell)))
        continue;
      fe_values.reinit(cell);
      const materials::ConstitutiveLaw& law = cell_material(cell);
      cell_matrix = 0;
      cell_fint = 0;
      cell_fext = 0;
      // The cell's values through the cached local indices (element access to a Trilinos
      // vector is a map lookup per DoF).
      get_cell_values(u_ghost_, cell, local_u);
      fe_values[displacements].get_function_gradients_from_local_dof_values(local_u, grads);
      if (bbar) {
        mean_dilatation.reinit(fe_values, comp);
        average_dilatation = mean_dilatation.average_dilatation(grads);
      }
      if (fbar) {
        unsigned int worst = 0;
        if (!f_bar.reinit(fe_values, comp, grads, worst))
          throw NumericalFailure(
              "inverted element (det F = " + std::to_string(f_bar.jacobian(worst)) +
                  ", cell mean " + std::to_string(f_bar.mean_jacobian()) + ")",
              quadrature_point_location<dim>(cell, worst),
              "the cell is crushed: take a smaller CFL safety factor, refine "
              "where it folds, or convert such cells to particles");
        std::fill(fbar_force.begin(), fbar_force.end(), 0.0);
      }

      for (unsigned int q = 0; q < nq; ++q) {
        const std::size_t idx = cell->active_cell_index() * nq + q;
        const QuadraturePointData& old = committed_[idx];
        QuadraturePointData& tr = trial_[idx];
        const Point<dim>& xq = fe_values.quadrature_point(q);
        double dT = 0.0;
        if (temperature_field_) // blended like load_blend(): from the previous solve's field
          dT = load_factor * dT_target_[idx] +
               (loaded_ && load_factor < 1.0 ? (1.0 - load_factor) * dT_start_[idx] : 0.0);
        else if (temperature_change_)
          dT = load_blend(*temperature_change_, xq, 0, load_factor);
        Tensor2 H = padded_gradient<dim>(grads[q]);
        if (bbar)
          MeanDilatation<dim>::project(H, average_dilatation);
        if (fbar)
          H = f_bar.modified_gradient(q);

        Tensor2 S; // stress conjugate to ∇u: σ or P
        try {
          S = point_update_(law, H, dT, old, tr, with_matrix ? A : nullptr);
        } catch (const NumericalFailure& e) {
          throw NumericalFailure(e.what_failed(), quadrature_point_location<dim>(cell, q),
                                 e.hint());
        }
        const double JxW = fe_values.JxW(q);
        Tensor<1, dim> body;
        if (body_force_)
          for (unsigned int c = 0; c < dim; ++c)
            body[c] = load_blend(*body_force_, xq, c, load_factor);
        if (bbar)
          for (unsigned int i = 0; i < n; ++i)
            beta[i] = mean_dilatation.beta(i, q);
        const double trace_S = bbar ? S[0][0] + S[1][1] + S[2][2] : 0.0;
        double trace_A[3][3] = {}; // Σ_a A(a,a,k,l)
        if (bbar && with_matrix)
          for (unsigned int k = 0; k < 3; ++k)
            for (unsigned int l = 0; l < 3; ++l)
              for (unsigned int a = 0; a < 3; ++a)
                trace_A[k][l] += A[a][a][k][l];
        if (fbar)
          f_bar.add_point_forces(q, S, fbar_force);
        for (unsigned int i = 0; i < n; ++i) {
          const unsigned int ci = comp[i];
          const Tensor<1, dim>& g = fe_values.shape_grad(i, q);
          double f = 0;
          if (!fbar)
            for (unsigned int J = 0; J < dim; ++J)
              f += S[ci][J] * g[J];
          if (bbar)
            f += beta[i] * trace_S;
          cell_fint(i) += f * JxW;
          cell_fext(i) += body[ci] * fe_values.shape_value(i, q) * JxW;
          if (with_matrix && bbar)
            for (unsigned int k = 0; k < 3; ++k)
              for (unsigned int l = 0; l < 3; ++l) {
                double s = beta[i] * trace_A[k][l];
                for (unsigned int J = 0; J < dim; ++J)
                  s += g[J] * A[ci][J][k][l];
                wb[i][3 * k + l] = s * JxW;
              }
          else if (with_matrix)
            for (unsigned int d = 0; d < dim; ++d)
              for (unsigned int L = 0; L < dim; ++L) {
                double s = 0;
                for (unsigned int J = 0; J < dim; ++J)
                  s += g[J] * A[ci][J][d][L];
                w[i][d * dim + L] = s * JxW;
              }
        }
        if (with_matrix && bbar)
          for (unsigned int i = 0; i < n; ++i) {
            const double trace_w = wb[i][0] + wb[i][4] + wb[i][8];
            for (unsigned int j = 0; j < n; ++j) {
              const Tensor<1, dim>& g = fe_values.shape_grad(j, q);
              double s = beta[j] * trace_w;
              for (unsigned int L = 0; L < dim; ++L)
                s += wb[i][3 * comp[j] + L] * g[L];
              cell_matrix(i, j) += s;
            }
          }
        else if (with_matrix)
          for (unsigned int i = 0; i < n; ++i)
            for (unsigned int j = 0; j < n; ++j) {
              const Tensor<1, dim>& g = fe_values.shape_grad(j, q);
              double s = 0;
              for (unsigned int L = 0; L < dim; ++L)
                s += w[i][comp[j] * dim + L] * g[L];
              cell_matrix(i, j) += s;
            }
      }

      if (fbar) {
        f_bar.finish_cell(fbar_force);
        for (unsigned int i = 0; i < n; ++i)
          cell_fint(i) += fbar_force[i];
      }

      // Tractions and pressures on the reference configuration.
      if (cell->at_boundary() && (!bcs_.traction().empty() || !bcs_.pressure().empty()))
        for (const unsigned int f : cell->face_indices()) {
          if (!cell->face(f)->at_boundary())
            continue;
          const types::boundary_id bid = cell->face(f)->boundary_id();
          const Point<dim> centre = cell->face(f)->center(); // by boundary id or region
          bool loaded = false;
          for (const auto& t : bcs_.traction())
            loaded |= t.acts_on(bid, centre);
          for (const auto& p : bcs_.pressure())
            loaded |= p.acts_on(bid, centre);
          if (!loaded)
            continue;
          fe_face.reinit(cell, f);
          for (unsigned int q = 0; q < face_quadrature_.size(); ++q) {
            const Point<dim>& xq = fe_face.quadrature_point(q);
            Tensor<1, dim> t;
            for (const auto& tr : bcs_.traction())
              if (tr.acts_on(bid, centre))
                for (unsigned int c = 0; c < dim; ++c)
                  t[c] += load_blend(*tr.function, xq, c, load_factor);
            for (const auto& p : bcs_.pressure())
              if (p.acts_on(bid, centre))
                t -= load_blend(*p.function, xq, 0, load_factor) * fe_face.normal_vector(q);
            for (unsigned int i = 0; i < n; ++i)
              cell_fext(i) += t[comp[i]] * fe_face.shape_value(i, q) * fe_face.JxW(q);
          }
        }

      // Tractions on the cavity wall (time-independent: in full once loaded).
      if (cavity_traction_ && !active_.empty()) {
        const double scale = loaded_ ? 1.0 : load_factor;
        cavity_wall::for_each_face<dim>(
            cell, [&](const auto& other) { return active_[other->active_cell_index()]; }, fe_face,
            fe_subface,
            [&](const FEFaceValuesBase<dim>& fv) {
              for (unsigned int q = 0; q < fv.n_quadrature_points; ++q) {
                const Tensor<1, dim> t =
                    scale * cavity_traction_(fv.quadrature_point(q), fv.normal_vector(q));
                for (unsigned int i = 0; i < n; ++i)
                  cell_fext(i) += t[comp[i]] * fv.shape_value(i, q) * fv.JxW(q);
              }
            });
      }

      cell->get_dof_indices(dofs);
      for (unsigned int i = 0; i < n; ++i)
        cell_rhs(i) = cell_fext(i) - cell_fint(i);
      if (assembly_sign_ != 1.0)
        cell_matrix *= assembly_sign_;
      if (with_matrix)
        constraints.distribute_local_to_global(cell_matrix, cell_rhs, dofs, matrix, rhs_);
      else
        constraints.distribute_local_to_global(cell_rhs, dofs, rhs_);
      f_int.add(dofs, cell_fint);
      f_ext.add(dofs, cell_fext);
    } catch (...) {
      failure = std::current_exception();
    }
  }
  // The compresses first (collective, every rank reaches them): entries bound for other ranks
  // must not stay buffered in the vectors into the next assembly after a failure.
  if (with_matrix)
    matrix.compress(VectorOperation::add);
  rhs_.compress(VectorOperation::add);
  f_int.compress(VectorOperation::add);
  f_ext.compress(VectorOperation::add);
  raise_on_every_rank(failure, comm_);
  if (with_matrix && !assembly_cells_ && !assemble_into_explicit_matrix_)
    regularise_untouched_rows(matrix, constraints);
  raw_residual_ = f_int;
  raw_residual_ -= f_ext;

  AssemblyNorms norms;
  norms.free_residual = rhs_.l2_norm();
  norms.reference = std::max(f_int.l2_norm(), f_ext.l2_norm());
  if (!std::isfinite(norms.free_residual))
    throw NumericalFailure("non-finite residual", "global assembly",
                           "check material parameters and boundary conditions");
  return norms;
}

template <int dim>
void MechanicsSolver<dim>::regularise_untouched_rows(
    MatrixType& matrix, const AffineConstraints<double>& constraints) const {
  // A constrained DoF that no active cell touches (an orphan among deactivated cells, or a
  // hanging node of deactivated cells only) gets no entry from distribute_local_to_global:
  // its row is zero and the matrix singular. AMG then returns a wrong update without a word
  // and a direct solver fails; the mean diagonal keeps the row regular, and the constraint
  // sets the DoF's value whatever the row says.
  double sum = 0;
  unsigned long count = 0;
  std::vector<types::global_dof_index> empty;
  for (const auto dof : owned_) {
    const double d = matrix.diag_element(dof);
    if (d != 0) {
      sum += std::abs(d);
      ++count;
    } else if (constraints.is_constrained(dof))
      empty.push_back(dof);
  }
  sum = Utilities::MPI::sum(sum, comm_);
  count = Utilities::MPI::sum(count, comm_);
  const unsigned long n_empty =
      Utilities::MPI::sum(static_cast<unsigned long>(empty.size()), comm_);
  if (n_empty == 0)
    return;
  const double scale = count > 0 ? sum / count : 1.0;
  for (const auto dof : empty)
    matrix.set(dof, dof, scale);
  matrix.compress(VectorOperation::insert);
}

template <int dim>
const typename MechanicsSolver<dim>::VectorType& MechanicsSolver<dim>::evaluate_residual() {
  if (!is_setup_)
    setup();
  target_time_ = time_;
  loaded_ = false;
  if (temperature_field_)
    evaluate_temperature_field(dT_target_);
  assemble(false, 1.0, hanging_);
  trial_ = committed_;
  return raw_residual_;
}

template <int dim>
const typename MechanicsSolver<dim>::MatrixType& MechanicsSolver<dim>::evaluate_tangent() {
  if (!is_setup_)
    setup();
  target_time_ = time_;
  loaded_ = false;
  if (temperature_field_)
    evaluate_temperature_field(dT_target_);
  assemble(true, 1.0, hanging_);
  trial_ = committed_;
  return matrix_;
}

template <int dim>
double MechanicsSolver<dim>::cavity_integral(
    const std::function<double(const Point<dim>&, const Tensor<1, dim>&)>& f) const {
  double local = 0;
  if (!active_.empty()) {
    FEFaceValues<dim> fe_face(*mapping_, fe_, face_quadrature_,
                              update_quadrature_points | update_normal_vectors | update_JxW_values);
    FESubfaceValues<dim> fe_subface(*mapping_, fe_, face_quadrature_,
                                    update_quadrature_points | update_normal_vectors |
                                        update_JxW_values);
    for (const auto& cell : dof_handler_.active_cell_iterators())
      if (cell->is_locally_owned() && is_active(cell))
        cavity_wall::for_each_face<dim>(
            cell, [&](const auto& other) { return active_[other->active_cell_index()]; }, fe_face,
            fe_subface,
            [&](const FEFaceValuesBase<dim>& fv) {
              for (unsigned int q = 0; q < fv.n_quadrature_points; ++q)
                local += f(fv.quadrature_point(q), fv.normal_vector(q)) * fv.JxW(q);
            });
  }
  return Utilities::MPI::sum(local, comm_);
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template double MechanicsSolver<dim>::load_blend(Function<dim>&, const Point<dim>&,              \
                                                   unsigned int, double) const;                    \
  template typename MechanicsSolver<dim>::AssemblyNorms MechanicsSolver<dim>::assemble(            \
      bool, double, const AffineConstraints<double>&);                                             \
  template double MechanicsSolver<dim>::cavity_integral(                                           \
      const std::function<double(const Point<dim>&, const Tensor<1, dim>&)>&) const;               \
  template void MechanicsSolver<dim>::regularise_untouched_rows(                                   \
      MatrixType&, const AffineConstraints<double>&) const;                                        \
  template const typename MechanicsSolver<dim>::VectorType&                                        \
  MechanicsSolver<dim>::evaluate_residual();                                                       \
  template const typename MechanicsSolver<dim>::MatrixType&                                        \
  MechanicsSolver<dim>::evaluate_tangent();
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
