// Assembly of MechanicsSolver: internal and external forces and the consistent tangent over the
// active cells, with loads blended along the quasi-static load path.

#include "fem/mechanics_solver.h"

#include "base/collective_failure.h"
#include "base/exceptions.h"
#include "base/scoped_time.h"
#include "fem/f_bar.h"
#include "fem/mean_dilatation.h"

#include <deal.II/base/work_stream.h>
#include <deal.II/fe/fe_values.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
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
  // Without a blend the function stays at target_time_, set once before the cell loop
  // (assemble(), the only caller): the loop's threads only read it.
  if (!(loaded_ && load_factor < 1.0))
    return load_factor * f.value(x, c);
  f.set_time(target_time_);
  double value = load_factor * f.value(x, c);
  f.set_time(previous_time_);
  value += (1.0 - load_factor) * f.value(x, c);
  return value;
}

template <int dim>
typename MechanicsSolver<dim>::AssemblyNorms
MechanicsSolver<dim>::assemble(bool with_matrix, double load_factor,
                               const AffineConstraints<double>& constraints) {
  ScopedTime timer(timings_.assembly);
  MatrixType& matrix = assemble_into_explicit_matrix_ ? explicit_matrix_ : matrix_;
  if (with_matrix)
    matrix = 0;
  rhs_ = 0;
  VectorType f_int(owned_, comm_);
  external_force_.reinit(owned_, comm_); // kept for the energy account
  VectorType& f_ext = external_force_;

  const unsigned int nq = quadrature_.size(), n = fe_.n_dofs_per_cell();
  const FEValuesExtractors::Vector displacements(0);
  std::vector<unsigned int> comp(n);
  for (unsigned int i = 0; i < n; ++i)
    comp[i] = fe_.system_to_component_index(i).first;
  // B-bar (mean_dilatation.h): H̄ at the points, δH̄_i = g_i ⊗ e_{c_i} + β_i I₃ in the force
  // and W_i = δH̄_i : A JxW (3×3, with zz in plane strain) in the tangent.
  const bool bbar = prm_.volumetric_locking == "bbar";
  // F-bar (f_bar.h): P̄ = P(F̄) at the points and its own force; no tangent.
  const bool fbar = prm_.volumetric_locking == "fbar";
  if (fbar && with_matrix)
    throw std::logic_error("F-bar has no consistent tangent: explicit steps only");

  // Per thread: the finite-element values and the point loop's scratch.
  struct Scratch {
    Scratch(const Mapping<dim>& mapping, const FiniteElement<dim>& fe, const Quadrature<dim>& q,
            const Quadrature<dim - 1>& face_q, bool bbar, bool fbar)
        : fe_values(mapping, fe, q,
                    update_values | update_gradients | update_quadrature_points |
                        update_JxW_values),
          fe_face(mapping, fe, face_q,
                  update_values | update_quadrature_points | update_normal_vectors |
                      update_JxW_values),
          fe_subface(mapping, fe, face_q,
                     update_values | update_quadrature_points | update_normal_vectors |
                         update_JxW_values),
          grads(q.size()), local_u(fe.n_dofs_per_cell()), w(fe.n_dofs_per_cell()),
          beta(fe.n_dofs_per_cell()), wb(bbar ? fe.n_dofs_per_cell() : 0),
          fbar_force(fbar ? fe.n_dofs_per_cell() : 0) {}
    Scratch(const Scratch& o)
        : fe_values(o.fe_values.get_mapping(), o.fe_values.get_fe(), o.fe_values.get_quadrature(),
                    o.fe_values.get_update_flags()),
          fe_face(o.fe_face.get_mapping(), o.fe_face.get_fe(), o.fe_face.get_quadrature(),
                  o.fe_face.get_update_flags()),
          fe_subface(o.fe_subface.get_mapping(), o.fe_subface.get_fe(),
                     o.fe_subface.get_quadrature(), o.fe_subface.get_update_flags()),
          grads(o.grads), local_u(o.local_u), w(o.w), beta(o.beta), wb(o.wb),
          fbar_force(o.fbar_force) {}
    FEValues<dim> fe_values;
    FEFaceValues<dim> fe_face;
    FESubfaceValues<dim> fe_subface;
    std::vector<Tensor<2, dim>> grads;
    std::vector<double> local_u;
    std::vector<std::array<double, dim * dim>> w; // w_i[d][L] = Σ_J ∇N_i,J A(c_i,J,d,L) JxW
    double A[3][3][3][3];
    MeanDilatation<dim> mean_dilatation;
    std::vector<double> beta;
    std::vector<std::array<double, 9>> wb;
    FBar<dim> f_bar;
    std::vector<double> fbar_force;
  };
  // Per cell: what the copier adds to the global matrix and vectors.
  struct Copy {
    FullMatrix<double> cell_matrix;
    Vector<double> cell_rhs, cell_fint, cell_fext;
    std::vector<types::global_dof_index> dofs;
    bool filled = false;
  };

  // The cells to assemble, in the active-cell order the serial loop took.
  std::vector<typename DoFHandler<dim>::active_cell_iterator> cells;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      cells.push_back(cell);
  // The load functions at the target time: the threads only read them (load_blend).
  for (auto* f : {body_force_.get(), temperature_change_.get()})
    if (f)
      f->set_time(target_time_);
  for (const auto& t : bcs_.traction())
    t.function->set_time(target_time_);
  for (const auto& p : bcs_.pressure())
    p.function->set_time(target_time_);

  // A point that fails (inverted, non-finite), or anything else thrown for a cell, stops the
  // cells not yet begun; the first failing cell in the loop's order is kept, and every rank
  // then meets in raise_on_every_rank after the collective compresses below.
  std::exception_ptr failure;
  std::atomic<std::size_t> failure_at{cells.size()};
  std::mutex failure_mutex;
  const auto record_failure = [&](std::size_t at) {
    std::lock_guard<std::mutex> lock(failure_mutex);
    if (at < failure_at.load()) {
      failure = std::current_exception();
      failure_at = at;
    }
  };
  using CellIt =
      typename std::vector<typename DoFHandler<dim>::active_cell_iterator>::const_iterator;
  const auto worker = [&](const CellIt& it, Scratch& scratch, Copy& copy) {
    copy.filled = false;
    const std::size_t at = static_cast<std::size_t>(it - cells.cbegin());
    if (at > failure_at.load(std::memory_order_relaxed)) // an earlier cell failed
      return;
    const auto& cell = *it;
    auto& fe_values = scratch.fe_values;
    auto& fe_face = scratch.fe_face;
    auto& fe_subface = scratch.fe_subface;
    auto& grads = scratch.grads;
    auto& local_u = scratch.local_u;
    auto& w = scratch.w;
    auto& A = scratch.A;
    auto& mean_dilatation = scratch.mean_dilatation;
    auto& beta = scratch.beta;
    auto& wb = scratch.wb;
    auto& f_bar = scratch.f_bar;
    auto& fbar_force = scratch.fbar_force;
    auto& cell_matrix = copy.cell_matrix;
    auto& cell_rhs = copy.cell_rhs;
    auto& cell_fint = copy.cell_fint;
    auto& cell_fext = copy.cell_fext;
    auto& dofs = copy.dofs;
    double average_dilatation = 0;
    try {
      cell_matrix.reinit(with_matrix ? n : 0, with_matrix ? n : 0);
      cell_rhs.reinit(n);
      cell_fint.reinit(n);
      cell_fext.reinit(n);
      dofs.resize(n);
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
      copy.filled = true;
    } catch (...) {
      record_failure(at);
    }
  };
  // The copier runs one cell at a time, in order; what it throws (a Trilinos error) is
  // recorded like a cell's failure, past every cell, and raised collectively below.
  const auto copier = [&](const Copy& copy) {
    if (!copy.filled || failure_at.load() < cells.size())
      return;
    try {
      if (with_matrix)
        constraints.distribute_local_to_global(copy.cell_matrix, copy.cell_rhs, copy.dofs, matrix,
                                               rhs_);
      else
        constraints.distribute_local_to_global(copy.cell_rhs, copy.dofs, rhs_);
      f_int.add(copy.dofs, copy.cell_fint);
      f_ext.add(copy.dofs, copy.cell_fext);
    } catch (...) {
      record_failure(cells.size() - 1);
    }
  };
  Scratch scratch(*mapping_, fe_, quadrature_, face_quadrature_, bbar, fbar);
  Copy copy;
  if (loaded_ && load_factor < 1.0) {
    // Blending the loads sets the functions' times per value (load_blend): one thread.
    for (auto it = cells.cbegin(); it != cells.cend(); ++it) {
      worker(it, scratch, copy);
      copier(copy);
    }
  } else
    // The copier runs in the cells' order (a serial, in-order stage of WorkStream's pipeline):
    // the sums are those of the serial loop, bit for bit, on any number of threads.
    WorkStream::run(cells.cbegin(), cells.cend(), worker, copier, scratch, copy);
  // The compresses first (collective, every rank reaches them): entries bound for other ranks
  // must not stay buffered in the vectors into the next assembly after a failure.
  if (with_matrix)
    matrix.compress(VectorOperation::add);
  rhs_.compress(VectorOperation::add);
  f_int.compress(VectorOperation::add);
  f_ext.compress(VectorOperation::add);
  raise_on_every_rank(failure, comm_);
  if (with_matrix && !assemble_into_explicit_matrix_)
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
