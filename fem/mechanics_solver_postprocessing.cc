// Results of MechanicsSolver: reactions, energies, momentum, plastic work and its heating rate,
// cell averages and VTU output.

#include "fem/mechanics_solver.h"

#include "fem/f_bar.h"
#include "fem/point_update.h"

#include "fem/materials/j2_plasticity.h"
#include "fem/materials/tensor_tools.h"

#include "base/scoped_time.h"

#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/numerics/data_out.h>

#include <cmath>

namespace spinesim::fem {

using namespace dealii;

namespace {

// Per locally owned cell (by active cell index; others 0): the mean of value() over its points.
template <int dim, typename PointValue>
Vector<float> cell_averages(const MechanicsSolver<dim>& solver, PointValue value) {
  Vector<float> out(solver.dof_handler().get_triangulation().n_active_cells());
  for (const auto& cell : solver.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned()) {
      double s = 0;
      const auto data = solver.quadrature_point_data(cell);
      for (const auto& d : data)
        s += value(d);
      out(cell->active_cell_index()) = s / data.size();
    }
  return out;
}

} // namespace

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::reaction_force(types::boundary_id id) const {
  return Utilities::MPI::sum(local_reaction_force(id), comm_); // one reduction for all components
}

template <int dim>
const typename MechanicsSolver<dim>::ReactionDofs&
MechanicsSolver<dim>::reaction_dofs(const std::set<types::boundary_id>& ids) const {
  auto it = reaction_dofs_.find(ids);
  if (it != reaction_dofs_.end())
    return it->second;
  ReactionDofs& r = reaction_dofs_[ids];
  const IndexSet on_boundary = DoFTools::extract_boundary_dofs(dof_handler_, ComponentMask(), ids);
  for (unsigned int c = 0; c < dim; ++c)
    for (const auto i : on_boundary& component_dofs_[c])
      r.dofs.emplace_back(i, c);
  // Hanging DoFs whose masters lie on the boundary, wherever those masters are owned: a
  // ghosted indicator of the boundary's DoFs (collective, once per set of ids and setup).
  VectorType flag(owned_, comm_), flag_ghosted(owned_, relevant_, comm_);
  for (const auto& [i, c] : r.dofs)
    flag(i) = 1.0;
  flag.compress(VectorOperation::insert);
  flag_ghosted = flag;
  for (const auto& line : hanging_.get_lines()) {
    // A hanging DoF on the boundary is counted as it is (its masters are there too).
    if (!owned_.is_element(line.index) || flag_ghosted(line.index) != 0.0)
      continue;
    double weight = 0;
    for (const auto& [master, w] : line.entries)
      if (flag_ghosted(master) != 0.0)
        weight += w;
    if (weight != 0.0)
      r.shares.push_back(
          {line.index, owned_component_[owned_.index_within_set(line.index)], weight});
  }
  return r;
}

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::reaction_force(const std::set<types::boundary_id>& ids) const {
  const ReactionDofs& r = reaction_dofs(ids);
  Tensor<1, dim> f;
  for (const auto& [i, c] : r.dofs)
    f[c] += raw_residual_(i);
  for (const auto& share : r.shares)
    f[share.component] += share.weight * raw_residual_(share.dof);
  return Utilities::MPI::sum(f, comm_);
}

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::local_reaction_force(types::boundary_id id) const {
  const ReactionDofs& r = reaction_dofs({id});
  Tensor<1, dim> f;
  for (const auto& [i, c] : r.dofs)
    f[c] += raw_residual_(i);
  for (const auto& share : r.shares)
    f[share.component] += share.weight * raw_residual_(share.dof);
  return f;
}

template <int dim>
void MechanicsSolver<dim>::mark_plastic_work() {
  if (!is_setup_)
    setup();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  plastic_work_mark_.assign(tria_.n_active_cells(), 0.0);
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      double w = 0;
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        w += data[q].state.plastic_work * fe_values.JxW(q);
      plastic_work_mark_[cell->active_cell_index()] = w;
    }
  plastic_work_mark_time_ = time_;
}

template <int dim>
Vector<double> MechanicsSolver<dim>::cell_plastic_dissipation_rate() const {
  Vector<double> rate(tria_.n_active_cells());
  const double elapsed = time_ - plastic_work_mark_time_;
  if (!is_setup_ || plastic_work_mark_.size() != tria_.n_active_cells() || !(elapsed > 0))
    return rate;
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      double w = 0, volume = 0;
      for (unsigned int q = 0; q < quadrature_.size(); ++q) {
        w += data[q].state.plastic_work * fe_values.JxW(q);
        volume += fe_values.JxW(q);
      }
      rate(cell->active_cell_index()) =
          (w - plastic_work_mark_[cell->active_cell_index()]) / (volume * elapsed);
    }
  return rate;
}

template <int dim>
double MechanicsSolver<dim>::plastic_work() const {
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  double w = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        w += data[q].state.plastic_work * fe_values.JxW(q);
    }
  return Utilities::MPI::sum(w, comm_);
}

template <int dim>
std::optional<std::vector<materials::Tensor2>>
MechanicsSolver<dim>::current_deformation_gradients(const CellIterator& cell) const {
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_gradients | update_JxW_values);
  fe_values.reinit(cell);
  const unsigned int n = fe_.n_dofs_per_cell(), nq = quadrature_.size();
  std::vector<double> local(n);
  get_cell_values(u_ghost_, cell, local);
  std::vector<Tensor<2, dim>> grads(nq);
  fe_values[FEValuesExtractors::Vector(0)].get_function_gradients_from_local_dof_values(local,
                                                                                        grads);
  std::vector<materials::Tensor2> F(nq);
  if (prm_.volumetric_locking == "fbar") {
    std::vector<unsigned int> comp(n);
    for (unsigned int i = 0; i < n; ++i)
      comp[i] = fe_.system_to_component_index(i).first;
    FBar<dim> f_bar;
    unsigned int worst = 0;
    if (!f_bar.reinit(fe_values, comp, grads, worst))
      return std::nullopt;
    for (unsigned int q = 0; q < nq; ++q)
      F[q] = materials::Tensor2(unit_symmetric_tensor<3>()) + f_bar.modified_gradient(q);
  } else {
    for (unsigned int q = 0; q < nq; ++q)
      F[q] = materials::Tensor2(unit_symmetric_tensor<3>()) + padded_gradient<dim>(grads[q]);
  }
  return F;
}

template <int dim>
Tensor<2, dim> MechanicsSolver<dim>::stress_integral() const {
  refresh_states();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  Tensor<2, dim> integral;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        for (unsigned int i = 0; i < dim; ++i)
          for (unsigned int j = 0; j < dim; ++j)
            integral[i][j] += data[q].work_stress[i][j] * fe_values.JxW(q);
    }
  return Utilities::MPI::sum(integral, comm_);
}

template <int dim>
typename MechanicsSolver<dim>::ResidualVirial
MechanicsSolver<dim>::residual_virial(const Point<dim>& origin) const {
  // Σ_a X_a ⊗ f_int,a = ∫ σ dV holds DoF by DoF for an isoparametric element (Σ_a X_a N_a = X),
  // hanging DoFs included: the linear path condenses their rows into their masters, whose
  // support points interpolate theirs.
  std::map<types::global_dof_index, Point<dim>> support;
  DoFTools::map_dofs_to_support_points(*mapping_, dof_handler_, support);
  std::vector<std::uint8_t> kind(owned_.n_elements(), 0); // 1 Dirichlet, 2 driven
  if (dirichlet_dofs_ready_) {
    for (const auto& list : dirichlet_dofs_)
      for (const auto& b : list)
        kind[b.local] = 1;
  } else {
    for (const auto& condition : bcs_.dirichlet()) {
      std::map<types::global_dof_index, double> dofs;
      BoundaryConditions<dim>::interpolate(condition, *mapping_, dof_handler_,
                                           Functions::ZeroFunction<dim>(dim), dofs);
      for (const auto& [dof, zero] : dofs)
        if (owned_.is_element(dof))
          kind[owned_.index_within_set(dof)] = 1;
    }
  }
  for (const auto& [dof, value] : driven_)
    if (owned_.is_element(dof) && kind[owned_.index_within_set(dof)] == 0)
      kind[owned_.index_within_set(dof)] = 2;
  Tensor<2, dim> part[3];
  Tensor<1, dim> force[3];
  std::size_t k = 0;
  for (auto it = owned_.begin(); it != owned_.end(); ++it, ++k) {
    const double r = raw_residual_(*it);
    if (r == 0.0)
      continue;
    const Tensor<1, dim> X = support.at(*it) - origin;
    const unsigned int c = owned_component_[k];
    for (unsigned int i = 0; i < dim; ++i)
      part[kind[k]][i][c] += X[i] * r;
    force[kind[k]][c] += r;
  }
  ResidualVirial v;
  v.rest = Utilities::MPI::sum(part[0], comm_);
  v.dirichlet = Utilities::MPI::sum(part[1], comm_);
  v.driven = Utilities::MPI::sum(part[2], comm_);
  v.rest_force = Utilities::MPI::sum(force[0], comm_);
  v.dirichlet_force = Utilities::MPI::sum(force[1], comm_);
  v.driven_force = Utilities::MPI::sum(force[2], comm_);
  return v;
}

template <int dim>
double MechanicsSolver<dim>::strain_energy() const {
  if (explicit_matrix_ready_ && linear_explicit()) {
    // Linear path: ½ uᵀ K u (K over the active cells) without refreshing the point states,
    // over the unconstrained DoFs: a hanging node's row holds no stiffness of its own (its
    // cells' stiffness went to its masters), only a diagonal entry that keeps K regular. Taken
    // whether or not the point states are fresh, so that the same state gives the same energy
    // to the bit (history.csv's last row and summary.json read it before and after the point
    // states are refreshed for the stresses; the point-state integral differs in round-off).
    VectorType Ku(owned_, comm_);
    explicit_matrix_.vmult(Ku, u_);
    double stored2 = 0;
    for (const auto dof : owned_)
      if (!hanging_.is_constrained(dof))
        stored2 += u_(dof) * Ku(dof);
    return 0.5 * Utilities::MPI::sum(stored2, comm_);
  }
  refresh_states();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  double e = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      const auto& law = cell_material(cell);
      const auto* j2 = dynamic_cast<const materials::J2Plasticity*>(&law);
      if (prm_.kinematics == "small_strain" && j2 != nullptr) {
        // Work minus plastic work, integrated over the load steps, is the stored energy only
        // in the limit of small steps (a step across yield adds trapezoid work against
        // backward-Euler dissipation): take it from the stress.
        for (unsigned int q = 0; q < quadrature_.size(); ++q)
          e += j2->stored_energy_density(data[q].cauchy_stress) * fe_values.JxW(q);
        continue;
      }
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        e += (data[q].work_density - data[q].state.plastic_work) * fe_values.JxW(q);
    }
  return Utilities::MPI::sum(e, comm_);
}

template <int dim>
double MechanicsSolver<dim>::max_von_mises() const {
  refresh_states();
  const unsigned int nq = quadrature_.size();
  double m = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      const std::size_t first = cell->active_cell_index() * nq;
      for (std::size_t k = first; k < first + nq; ++k)
        m = std::max(m, materials::von_mises(committed_[k].cauchy_stress));
    }
  return Utilities::MPI::max(m, comm_);
}

template <int dim>
double MechanicsSolver<dim>::kinetic_energy() const {
  // Local arrays in the order of owned_ (element access through Trilinos is a map lookup).
  const double* m = lumped_mass_.begin();
  const double* v = v_.begin();
  double e = 0;
  for (std::size_t k = 0; k < owned_.n_elements(); ++k)
    e += 0.5 * m[k] * v[k] * v[k];
  return Utilities::MPI::sum(e, comm_);
}

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::momentum() const {
  const double* m = lumped_mass_.begin();
  const double* v = v_.begin();
  Tensor<1, dim> p;
  for (std::size_t k = 0; k < owned_component_.size(); ++k)
    p[owned_component_[k]] += m[k] * v[k];
  return Utilities::MPI::sum(p, comm_);
}

template <int dim>
Vector<float> MechanicsSolver<dim>::cell_von_mises() const {
  return cell_averages(
      *this, [](const QuadraturePointData& d) { return materials::von_mises(d.cauchy_stress); });
}

template <int dim>
Vector<float> MechanicsSolver<dim>::cell_equivalent_plastic_strain() const {
  return cell_averages(
      *this, [](const QuadraturePointData& d) { return d.state.equivalent_plastic_strain; });
}

template <int dim>
std::string MechanicsSolver<dim>::write_output(
    const std::string& directory, const std::string& basename, unsigned int cycle,
    const std::vector<std::pair<std::string, const Vector<float>*>>& cell_fields) const {
  refresh_states();
  ScopedTime timer(timings_.output);
  DataOut<dim> data_out;
  data_out.attach_dof_handler(dof_handler_);
  const std::vector<std::string> names(dim, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> interpretation(
      dim, DataComponentInterpretation::component_is_part_of_vector);
  data_out.add_data_vector(u_ghost_, names, DataOut<dim>::type_dof_data, interpretation);
  const Vector<float> vm = cell_von_mises(), ep = cell_equivalent_plastic_strain();
  Vector<float> material_id(tria_.n_active_cells()), subdomain(tria_.n_active_cells()),
      active(tria_.n_active_cells());
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      material_id(cell->active_cell_index()) = cell->material_id();
      subdomain(cell->active_cell_index()) = tria_.locally_owned_subdomain();
      active(cell->active_cell_index()) = is_active(cell) ? 1.f : 0.f;
    }
  data_out.add_data_vector(vm, "von_mises");
  data_out.add_data_vector(ep, "equivalent_plastic_strain");
  data_out.add_data_vector(material_id, "material_id");
  data_out.add_data_vector(subdomain, "subdomain");
  if (!active_.empty())
    data_out.add_data_vector(active, "fem_active");
  for (const auto& [name, field] : cell_fields) // one value per active cell (by index)
    data_out.add_data_vector(*field, name);
  data_out.build_patches(*mapping_, prm_.fe_degree);
  // zlib at its fastest level: with deal.II's default (best_compression) the output of the
  // cracked-plate scenes took 1.4 s of a 6.7 s run; best_speed takes a tenth of that.
  DataOutBase::VtkFlags flags;
  flags.compression_level = DataOutBase::VtkFlags::best_speed;
  data_out.set_flags(flags);
  const std::string dir =
      directory.empty() || directory.back() == '/' ? directory : directory + "/";
  return data_out.write_vtu_with_pvtu_record(dir, basename, cycle, comm_, 4);
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template Tensor<1, dim> MechanicsSolver<dim>::reaction_force(types::boundary_id) const;          \
  template Tensor<1, dim> MechanicsSolver<dim>::local_reaction_force(types::boundary_id) const;    \
  template Tensor<1, dim> MechanicsSolver<dim>::reaction_force(                                    \
      const std::set<types::boundary_id>&) const;                                                  \
  template const typename MechanicsSolver<dim>::ReactionDofs& MechanicsSolver<dim>::reaction_dofs( \
      const std::set<types::boundary_id>&) const;                                                  \
  template void MechanicsSolver<dim>::mark_plastic_work();                                         \
  template Vector<double> MechanicsSolver<dim>::cell_plastic_dissipation_rate() const;             \
  template double MechanicsSolver<dim>::plastic_work() const;                                      \
  template double MechanicsSolver<dim>::strain_energy() const;                                     \
  template Tensor<2, dim> MechanicsSolver<dim>::stress_integral() const;                           \
  template typename MechanicsSolver<dim>::ResidualVirial MechanicsSolver<dim>::residual_virial(    \
      const Point<dim>&) const;                                                                    \
  template std::optional<std::vector<materials::Tensor2>>                                          \
  MechanicsSolver<dim>::current_deformation_gradients(const CellIterator&) const;                  \
  template double MechanicsSolver<dim>::max_von_mises() const;                                     \
  template double MechanicsSolver<dim>::kinetic_energy() const;                                    \
  template Tensor<1, dim> MechanicsSolver<dim>::momentum() const;                                  \
  template Vector<float> MechanicsSolver<dim>::cell_von_mises() const;                             \
  template Vector<float> MechanicsSolver<dim>::cell_equivalent_plastic_strain() const;             \
  template std::string MechanicsSolver<dim>::write_output(                                         \
      const std::string&, const std::string&, unsigned int,                                        \
      const std::vector<std::pair<std::string, const Vector<float>*>>&) const;
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
