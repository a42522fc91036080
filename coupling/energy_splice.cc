#include "coupling/energy_splice.h"

#include "coupling/ghost_force_spread.h"
#include "coupling/mls_fit.h"
#include "coupling/point_bins.h"

#include "base/exceptions.h"
#include "fem/materials/constitutive_law.h"

#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/lapack_full_matrix.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
std::array<double, EnergySplice<dim>::n_modes>
EnergySplice<dim>::modes(const Point<dim>& x, unsigned int component) const {
  std::array<double, n_modes> a{};
  a[component] = 1.0;
  for (unsigned int b = 0; b < dim; ++b)
    a[dim + component * dim + b] = x[b] - centre_[b];
  return a;
}

template <int dim>
void EnergySplice<dim>::check() const {
  const auto& m = *state_.method;
  if (!m.driven_reactions(state_.particles, state_.bonds) ||
      !m.splice_energy_by_row(state_.particles, state_.bonds))
    throw InvalidInput("Coupling/Splice",
                       "= energy with particle method '" + m.name() +
                           "' as configured (its forces are not the gradient of an energy: "
                           "SPG smoothing every n > 1 steps)",
                       "Smoothing interval = 1 (SPG), or Coupling/Splice = overlap");
}

template <int dim>
double EnergySplice<dim>::owned_particle_energy() const {
  const auto E = state_.method->splice_energy_by_row(state_.particles, state_.bonds);
  if (!E)
    return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (unsigned int i = 0; i < E->size(); ++i)
    if (state_.is_owned(i))
      sum += (*E)[i];
  return sum;
}

template <int dim>
double EnergySplice<dim>::account_stored_energy() const {
  double e = owned_particle_energy();
  const double correction = current_correction_energy(); // collective
  return state_.rank == 0 ? e + correction : e;
}

template <int dim>
double EnergySplice<dim>::current_correction_energy() const {
  if (!ready_)
    return 0.0;
  dealii::Vector<double> alpha(n_modes), beta(n_modes), t(n_modes);
  correction_sums(alpha, beta);
  S_.vmult(t, alpha);
  return beta * alpha - 0.5 * (alpha * t);
}

template <int dim>
void EnergySplice<dim>::check_stored_energy() {
  if (!ready_)
    return;
  auto& fem = state_.fem;
  const double models = fem.linear_stored_energy() +
                        Utilities::MPI::sum(owned_particle_energy(), fem.mpi_communicator());
  const double correction = current_correction_energy();
  // Round-off of the sums is ~1e-12 of the models' energy; an indefinite mode grows past them.
  if (models + correction < -1e-6 * std::abs(models)) {
    std::ostringstream what;
    what << "the energy splice's stored energy is negative (FEM and particles " << models
         << " J, consistency correction " << correction << " J): a mode without stiffness grows";
    throw NumericalFailure(what.str(), "the FEM/particle interface",
                           "the correction was made for the intact material, and a crack that "
                           "cuts the body apart, or cuts it next to the interface, can leave it "
                           "without positive stiffness; keep cracks inside the particles, away "
                           "from the interface (a wider Coupling/Initial region or Conversion "
                           "region, Coupling/Buffer), end the run before the body separates, or "
                           "use Coupling/Splice = overlap (docs/coupling.md)");
  }
}

template <int dim>
void EnergySplice<dim>::spread_to_fem(const std::vector<Vector>& ghost_forces) {
  spread_ghost_forces(state_, ghost_forces, fem_reactions_, fem_reaction_values_);
}

template <int dim>
void EnergySplice<dim>::rebuild(const StepForces& split) {
  if (!on())
    return;
  check();
  ready_ = false;
  auto& fem = state_.fem;
  auto& particles = state_.particles;
  const unsigned int n = particles.size();
  const MPI_Comm comm = fem.mpi_communicator();
  const auto& owned = fem.locally_owned_dofs();
  const auto& dh = fem.dof_handler();
  const auto& fe = fem.fe();
  const unsigned int n_cell_dofs = fe.n_dofs_per_cell();
  const auto& unit = fe.get_unit_support_points();

  // Support points and components of the owned DoFs.
  dof_point_.assign(owned.n_elements(), Point<dim>());
  dof_component_.assign(owned.n_elements(), 0);
  std::vector<types::global_dof_index> dofs(n_cell_dofs);
  for (const auto& cell : dh.active_cell_iterators())
    if (cell->is_locally_owned()) {
      cell->get_dof_indices(dofs);
      for (unsigned int i = 0; i < n_cell_dofs; ++i)
        if (owned.is_element(dofs[i])) {
          const auto k = owned.index_within_set(dofs[i]);
          dof_point_[k] = fem.mapping().transform_unit_to_real_cell(cell, unit[i]);
          dof_component_[k] = fe.system_to_component_index(i).first;
        }
    }
  IndexSet relevant;
  DoFTools::extract_locally_relevant_dofs(dh, relevant);
  // Where each owned DoF sits in the FEM's ghosted vectors (their maps are in global order,
  // ghosts included, so owned entries are not first).
  {
    const auto& map = fem.displacement().trilinos_vector().Map();
    AssertThrow(map.SameAs(fem.velocity().trilinos_vector().Map()),
                ExcMessage("the FEM's displacement and velocity vectors differ in layout"));
    ghosted_lid_.resize(owned.n_elements());
    for (std::size_t k = 0; k < owned.n_elements(); ++k)
      ghosted_lid_[k] =
          map.LID(static_cast<TrilinosWrappers::types::int_type>(owned.nth_index_in_set(k)));
  }
  fem_reactions_.reinit(owned, relevant, comm, true);
  fem_reaction_values_.assign(owned.n_elements(), 0.0);

  // The affine modes about the centre of the free particles (conditioning of Aᵀ M A).
  centre_ = Point<dim>();
  unsigned int n_free = 0;
  for (unsigned int i = 0; i < n; ++i)
    if (state_.free[i]) {
      centre_ += particles.reference_position(i);
      ++n_free;
    }
  if (n_free > 0)
    centre_ /= n_free;

  // G = K A − T per gradient mode (translations create no force in either model), in the
  // K u = −f convention: the forces for u = ±ε H (x − c) (central differences, O(ε²) from the
  // tangent; ε = 1e-6 keeps the round-off of the forces at 1e-10 of G). The probes run on a
  // second instance of the method, made for the same material, on the same rows with every
  // bond intact and no history: the correction is that of the splice of the intact material,
  // so it neither heals cracks nor depends on where they are (what the particles do with a
  // crack or a surface is theirs), and the run's method keeps its state.
  std::vector<std::array<std::array<double, n_modes>, dim>> gp(n);
  std::vector<std::array<double, n_modes>> gf(owned.n_elements());
  {
    const double eps = 1e-6;
    const auto saved_u = particles.displacements();
    const auto saved_f = particles.forces();
    meshfree::BondList<dim> intact = state_.bonds;
    std::fill(intact.broken.begin(), intact.broken.end(), std::uint8_t(0));
    auto probe = state_.prm.make_method(state_.particle_material);
    std::vector<std::uint8_t> driven(n);
    for (unsigned int i = 0; i < n; ++i)
      driven[i] = state_.free[i] ? 0 : 1;
    probe->disable_breaking();
    probe->set_driven(std::move(driven));
    probe->initialise(particles, intact);
    probe->take_messages();
    std::vector<Vector> ghost_g(n);
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int b = 0; b < dim; ++b) {
        const unsigned int mode = dim + a * dim + b;
        std::fill(ghost_g.begin(), ghost_g.end(), Vector());
        for (const double sign : {1.0, -1.0}) {
          for (unsigned int i = 0; i < n; ++i) {
            Vector u;
            u[a] = sign * eps * (particles.reference_position(i)[b] - centre_[b]);
            particles.displacement(i) = u;
          }
          probe->compute_forces(particles, intact, false);
          const auto reactions = *probe->driven_reactions(particles, intact);
          const double w = -sign / (2 * eps);
          for (unsigned int i = 0; i < n; ++i) {
            if (state_.free[i] && state_.is_owned(i))
              for (unsigned int d = 0; d < dim; ++d)
                gp[i][d][mode] += w * particles.force(i)[d];
            else if (!state_.free[i])
              ghost_g[i] += w * reactions[i];
          }
        }
        spread_to_fem(ghost_g);
        for (std::size_t k = 0; k < gf.size(); ++k)
          gf[k][mode] = fem_reaction_values_[k];
      }
    particles.displacements() = saved_u;
    particles.forces() = saved_f;
    fem_reaction_values_.assign(owned.n_elements(), 0.0);
  }

  // T: the converted cells' FEM forces for each affine mode, at their nodes, handed to the
  // particles by the fits of those nodes (the interface DoFs' own fits, new ones elsewhere).
  auto& fits = fits_;
  fits.clear();
  replaced_.clear();
  for (const auto& entry : interface_.dofs())
    fits[entry.dof] = entry.weights;
  std::vector<Point<dim>> free_points;
  std::vector<unsigned int> free_index;
  for (unsigned int i = 0; i < n; ++i)
    if (state_.free[i]) {
      free_points.push_back(particles.reference_position(i));
      free_index.push_back(i);
    }
  PointBins<dim> bins(free_points, state_.prm.interface_radius * state_.spacing * 4);
  const auto fit_at = [&](const Point<dim>& X) {
    for (unsigned int attempt = 0; attempt < 3; ++attempt) {
      const double r = state_.prm.interface_radius * state_.spacing * (1.0 + 0.5 * attempt);
      if (const auto w =
              mls_linear_weights<dim>(X, free_points, bins.within(X, r), r, state_.spacing)) {
        std::vector<std::pair<unsigned int, double>> out;
        for (const auto& [k, phi] : *w)
          out.emplace_back(free_index[k], phi);
        return out;
      }
    }
    std::ostringstream where;
    where << "node at (" << X << ") of a converted cell";
    throw NumericalFailure("singular moving-least-squares fit for the splice correction",
                           where.str(),
                           "convert larger blocks (Coupling/Buffer), use more particles per cell "
                           "direction or a larger Coupling/Interface radius");
  };
  FEValues<dim> fe_values(fem.mapping(), fe, fem.quadrature(),
                          update_gradients | update_JxW_values);
  // Per mode, summed onto the owners of the DoFs (a replaced cell's node may be owned by a
  // neighbouring rank).
  std::vector<TrilinosWrappers::MPI::Vector> t_modes(n_modes);
  for (auto& v : t_modes)
    v.reinit(owned, relevant, comm, true);
  double t_scale = 0;
  for (const auto& cell : dh.active_cell_iterators()) {
    if (!cell->is_locally_owned() || fem.is_active(cell))
      continue;
    fe_values.reinit(cell);
    cell->get_dof_indices(dofs);
    // The elastic tangent of the cell's law, condensed to plane stress like the FEM's points.
    const auto C3 = fem.cell_material(cell).small_strain(materials::SymTensor2(), 0.0, {}).tangent;
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int b = 0; b < dim; ++b) {
        const unsigned int mode = dim + a * dim + b;
        materials::SymTensor2 strain; // sym(e_a ⊗ e_b) (one stored entry for a ≠ b)
        strain[a][b] = a == b ? 1.0 : 0.5;
        materials::SymTensor2 sigma = C3 * strain;
        if (dim == 2 && fem.parameters().plane_stress) {
          // σ_zz = 0: ε_zz = −C_zz:ε / C_zzzz, then σ = C:(ε + ε_zz e_z ⊗ e_z).
          materials::SymTensor2 ez;
          ez[2][2] = 1.0;
          const double ezz = -(ez * (C3 * strain)) / (ez * (C3 * ez));
          sigma = C3 * (strain + ezz * ez);
        }
        for (unsigned int i = 0; i < n_cell_dofs; ++i) {
          const unsigned int c = fe.system_to_component_index(i).first;
          double f = 0;
          for (unsigned int q = 0; q < fe_values.n_quadrature_points; ++q) {
            const auto grad = fe_values.shape_grad_component(i, q, c);
            for (unsigned int j = 0; j < dim; ++j)
              f += sigma[c][j] * grad[j] * fe_values.JxW(q);
          }
          if (f == 0)
            continue;
          t_scale = std::max(t_scale, std::abs(f));
          t_modes[mode](dofs[i]) += f;
        }
      }
  }
  for (auto& v : t_modes)
    v.compress(VectorOperation::add);
  for (std::size_t k = 0; k < owned.n_elements(); ++k) {
    const auto dof = owned.nth_index_in_set(k);
    std::array<double, n_modes> t{};
    bool any = false;
    for (unsigned int l = dim; l < n_modes; ++l) {
      t[l] = t_modes[l](dof);
      any = any || t[l] != 0;
    }
    if (!any)
      continue;
    replaced_[dof] = t;
    if (!fits.count(dof))
      fits.emplace(dof, fit_at(dof_point_[k]));
  }
  t_scale = Utilities::MPI::max(t_scale, comm);
  // Rows of R = −G without T (every component of the free particles, every owned DoF):
  // finalise() adds T and the driven DoFs' shares once the FEM's split of its DoFs is known.
  particle_rows_.clear();
  for (unsigned int i = 0; i < n; ++i)
    if (state_.free[i])
      for (unsigned int d = 0; d < dim; ++d) {
        Row row{i, d, {}};
        for (unsigned int l = 0; l < n_modes; ++l)
          row.r[l] = -gp[i][d][l];
        particle_rows_.push_back(row);
      }
  dof_rows_all_.clear();
  for (std::size_t k = 0; k < gf.size(); ++k) {
    Row row{static_cast<unsigned int>(k), 0, {}};
    for (unsigned int l = 0; l < n_modes; ++l)
      row.r[l] = -gf[k][l];
    dof_rows_all_.push_back(row);
  }
  t_scale_ = t_scale;
  finalise(split);
  splice_forces_.assign(n, Vector());
}

template <int dim>
void EnergySplice<dim>::finalise(const StepForces& forces) {
  auto& fem = state_.fem;
  const auto& particles = state_.particles;
  const auto& owned = fem.locally_owned_dofs();
  const std::size_t n_owned = owned.n_elements();
  // Rows by key: particle (i, d) and owned DoF k.
  std::map<std::pair<unsigned int, unsigned int>, std::size_t> particle_row;
  for (std::size_t r = 0; r < particle_rows_.size(); ++r)
    particle_row[{particle_rows_[r].index, particle_rows_[r].component}] = r;
  const auto add_to_particles = [&](const std::vector<std::pair<unsigned int, double>>& fit,
                                    unsigned int component, const std::array<double, n_modes>& r,
                                    double factor) {
    for (const auto& [p, phi] : fit) {
      auto& row = particle_rows_[particle_row.at({p, component})].r;
      for (unsigned int l = 0; l < n_modes; ++l)
        row[l] += factor * phi * r[l];
    }
  };
  // The ghosts' reactions on driven DoFs reach the particles through Φᵀ, like every force on
  // those DoFs: so does their share of G.
  for (const auto& entry : interface_.dofs()) {
    if (!owned.is_element(entry.dof))
      continue;
    const auto k = owned.index_within_set(entry.dof);
    if (forces.is_driven(k))
      add_to_particles(entry.weights, entry.component, dof_rows_all_[k].r, 1.0);
  }
  // T (R = −G = T − K A): the replaced cells' forces stay on prescribed DoFs; on the others
  // (driven, hanging, orphaned: none moves by itself) they go to the particles through the
  // node's fit.
  std::vector<std::array<double, n_modes>> prescribed_t(n_owned);
  for (const auto& [dof, t] : replaced_) {
    if (!owned.is_element(dof))
      continue;
    const auto k = owned.index_within_set(dof);
    if (forces.is_prescribed(k))
      for (unsigned int l = 0; l < n_modes; ++l)
        prescribed_t[k][l] += t[l];
    else
      add_to_particles(fits_.at(dof), dof_component_[k], t, 1.0);
  }
  // The particle rows are replicated until here: each rank added what its DoFs hand over.
  // Their sums go to the owners, who keep them.
  const MPI_Comm comm = fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) > 1) {
    std::vector<double> flat;
    flat.reserve(n_modes * particle_rows_.size());
    for (const auto& row : particle_rows_)
      flat.insert(flat.end(), row.r.begin(), row.r.end());
    Utilities::MPI::sum(flat, comm, flat);
    for (std::size_t r = 0; r < particle_rows_.size(); ++r)
      std::copy(flat.begin() + n_modes * r, flat.begin() + n_modes * (r + 1),
                particle_rows_[r].r.begin());
    particle_rows_.erase(
        std::remove_if(particle_rows_.begin(), particle_rows_.end(),
                       [&](const Row& row) { return !state_.is_owned(row.index); }),
        particle_rows_.end());
  }
  dof_rows_.clear();
  row_dofs_.clear();
  for (std::size_t k = 0; k < n_owned; ++k) {
    if (!forces.is_free(k) && !forces.is_prescribed(k))
      continue;
    row_dofs_.push_back(static_cast<unsigned int>(k));
    Row row = dof_rows_all_[k];
    for (unsigned int l = 0; l < n_modes; ++l)
      row.r[l] += prescribed_t[k][l];
    dof_rows_.push_back(row);
  }
  {
    // interface_mass_ratio(): the largest eigenvalue of M_p⁻¹ Φᵀ M_I Φ over the free particles'
    // components (M_I the lumped masses of the driven DoFs), by 60 power iterations with the
    // Rayleigh quotient (which approaches it from below; hence the factor 1.1).
    const double* m = fem.lumped_mass().begin();
    const unsigned int n = particles.size();
    std::vector<std::pair<std::size_t, const typename MlsInterface<dim>::Dof*>> driven;
    for (const auto& entry : interface_.dofs())
      if (owned.is_element(entry.dof)) {
        const auto k = owned.index_within_set(entry.dof);
        if (forces.is_driven(k))
          driven.emplace_back(k, &entry);
      }
    std::vector<double> x(dim * n, 0.0), y(dim * n);
    for (unsigned int i = 0; i < n; ++i)
      if (state_.free[i])
        for (unsigned int d = 0; d < dim; ++d)
          x[dim * i + d] = 1.0 + 0.5 * std::sin(1.0 + 7.0 * i + 3.0 * d); // not an eigenvector
    double lambda = 0;
    for (unsigned int it = 0; it < 60; ++it) {
      std::fill(y.begin(), y.end(), 0.0);
      for (const auto& [k, entry] : driven) {
        double u = 0;
        for (const auto& [p, phi] : entry->weights)
          u += phi * x[dim * p + entry->component];
        for (const auto& [p, phi] : entry->weights)
          y[dim * p + entry->component] += phi * m[k] * u;
      }
      if (Utilities::MPI::n_mpi_processes(comm) > 1)
        Utilities::MPI::sum(y, comm, y);
      // y = M_p⁻¹ Φᵀ M_I Φ x; λ ≈ xᵀ M_p y / xᵀ M_p x, then x = y / max |y|.
      double num = 0, den = 0, top = 0;
      for (unsigned int i = 0; i < n; ++i)
        for (unsigned int d = 0; d < dim; ++d) {
          auto& v = y[dim * i + d];
          v = state_.free[i] && particles.mass(i) > 0 ? v / particles.mass(i) : 0.0;
          num += particles.mass(i) * x[dim * i + d] * v;
          den += particles.mass(i) * x[dim * i + d] * x[dim * i + d];
          top = std::max(top, std::abs(v));
        }
      lambda = den > 0 ? num / den : 0.0;
      if (!(top > 0))
        break;
      for (std::size_t j = 0; j < y.size(); ++j)
        x[j] = y[j] / top;
    }
    interface_mass_ratio_ = 1.1 * lambda;
  }
  // Drop the rows without any entry (most of them: the correction is local).
  double r_max = 0;
  for (const auto* rows : {&particle_rows_, &dof_rows_})
    for (const auto& row : *rows)
      for (const double r : row.r)
        r_max = std::max(r_max, std::abs(r));
  r_max = Utilities::MPI::max(r_max, comm);
  ghost_force_relative_ = t_scale_ > 0 ? r_max / t_scale_ : 0.0;
  const auto prune = [&](std::vector<Row>& rows) {
    rows.erase(std::remove_if(rows.begin(), rows.end(),
                              [&](const Row& row) {
                                for (const double r : row.r)
                                  if (std::abs(r) > 1e-14 * r_max)
                                    return false;
                                return true;
                              }),
               rows.end());
  };
  prune(particle_rows_);
  prune(dof_rows_);

  // Aᵀ M A over the unknowns, and sym(RᵀA).
  FullMatrix<double> AMA(n_modes, n_modes), RA(n_modes, n_modes);
  const double* mass = fem.lumped_mass().begin();
  const auto add_mass = [&](double m, const std::array<double, n_modes>& a) {
    for (unsigned int i = 0; i < n_modes; ++i)
      for (unsigned int j = 0; j < n_modes; ++j)
        AMA(i, j) += m * a[i] * a[j];
  };
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i] && state_.is_owned(i))
      for (unsigned int d = 0; d < dim; ++d)
        add_mass(particles.mass(i), modes(particles.reference_position(i), d));
  for (const unsigned int k : row_dofs_)
    add_mass(mass[k], modes(dof_point_[k], dof_component_[k]));
  const auto add_row = [&](const Row& row, const std::array<double, n_modes>& a) {
    for (unsigned int i = 0; i < n_modes; ++i)
      for (unsigned int j = 0; j < n_modes; ++j)
        RA(i, j) += row.r[i] * a[j];
  };
  for (const auto& row : particle_rows_)
    add_row(row, modes(particles.reference_position(row.index), row.component));
  for (const auto& row : dof_rows_)
    add_row(row, modes(dof_point_[row.index], dof_component_[row.index]));
  const auto sum_matrix = [&](FullMatrix<double>& A) {
    if (Utilities::MPI::n_mpi_processes(comm) == 1)
      return;
    std::vector<double> flat(A.begin(), A.end());
    Utilities::MPI::sum(flat, comm, flat);
    std::copy(flat.begin(), flat.end(), A.begin());
  };
  sum_matrix(AMA);
  sum_matrix(RA);
  Q_.reinit(n_modes, n_modes);
  Q_.invert(AMA);
  S_.reinit(n_modes, n_modes);
  for (unsigned int i = 0; i < n_modes; ++i)
    for (unsigned int j = 0; j < n_modes; ++j)
      S_(i, j) = 0.5 * (RA(i, j) + RA(j, i));
  // The correction's spectrum: C = U B Uᵀ with U = [R, P], B = [[−S, I], [I, 0]] (in the
  // order (P, R)); the nonzero eigenvalues of M⁻¹C are those of B (Uᵀ M⁻¹ U), a 2m × 2m matrix:
  // Pᵀ M⁻¹ P = Q, Pᵀ M⁻¹ R = Q Aᵀ R, Rᵀ M⁻¹ R = Σ r rᵀ / m.
  {
    const unsigned int m = n_modes;
    FullMatrix<double> gram(2 * m, 2 * m), B(2 * m, 2 * m), BG(2 * m, 2 * m);
    FullMatrix<double> QAR(m, m);
    for (unsigned int i = 0; i < m; ++i)
      for (unsigned int j = 0; j < m; ++j)
        for (unsigned int k = 0; k < m; ++k)
          QAR(i, j) += Q_(i, k) * RA(j, k); // (Q Aᵀ R)_ij = Σ_k Q_ik (RᵀA)_jk
    const auto add_rr = [&](const Row& row, double mass) {
      for (unsigned int i = 0; i < m; ++i)
        for (unsigned int j = 0; j < m; ++j)
          gram(m + i, m + j) += row.r[i] * row.r[j] / mass;
    };
    for (const auto& row : particle_rows_)
      add_rr(row, particles.mass(row.index));
    for (const auto& row : dof_rows_)
      add_rr(row, mass[row.index]);
    sum_matrix(gram); // only the R block is filled yet
    for (unsigned int i = 0; i < m; ++i)
      for (unsigned int j = 0; j < m; ++j) {
        gram(i, j) = Q_(i, j);
        gram(i, m + j) = QAR(i, j);
        gram(m + j, i) = QAR(i, j);
        B(i, j) = -S_(i, j);
      }
    for (unsigned int i = 0; i < m; ++i) {
      B(i, m + i) = 1.0;
      B(m + i, i) = 1.0;
    }
    B.mmult(BG, gram);
    LAPACKFullMatrix<double> lapack(2 * m, 2 * m);
    lapack = BG;
    lapack.compute_eigenvalues();
    max_frequency_squared_ = 0;
    for (unsigned int i = 0; i < 2 * m; ++i)
      max_frequency_squared_ = std::max(max_frequency_squared_, lapack.eigenvalue(i).real());
  }
  ready_ = true;
}

template <int dim>
double EnergySplice<dim>::limit_step(double dt) const {
  if (!on() || !ready_ || !(max_frequency_squared_ > 0) || !std::isfinite(dt))
    return dt;
  return dt / std::sqrt(1.0 + max_frequency_squared_ * dt * dt / 4.0);
}

template <int dim>
void EnergySplice<dim>::take_particle_forces() {
  spread_to_fem(*state_.method->driven_reactions(state_.particles, state_.bonds));
}

template <int dim>
void EnergySplice<dim>::correction_sums(dealii::Vector<double>& alpha,
                                        dealii::Vector<double>& beta) const {
  // α = Pᵀu = Q Aᵀ M u and β = Rᵀu over the rows, at the current displacements.
  const auto& particles = state_.particles;
  const double* u_fem = state_.fem.displacement().trilinos_vector()[0]; // ghosted_lid_ order
  const double* mass = state_.fem.lumped_mass().begin();
  dealii::Vector<double> moment(n_modes);
  alpha = 0;
  beta = 0;
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i] && state_.is_owned(i))
      for (unsigned int d = 0; d < dim; ++d) {
        const auto a = modes(particles.reference_position(i), d);
        const double mu = particles.mass(i) * particles.displacement(i)[d];
        for (unsigned int l = 0; l < n_modes; ++l)
          moment[l] += a[l] * mu;
      }
  for (const unsigned int k : row_dofs_) {
    const auto a = modes(dof_point_[k], dof_component_[k]);
    const double mu = mass[k] * u_fem[ghosted_lid_[k]];
    for (unsigned int l = 0; l < n_modes; ++l)
      moment[l] += a[l] * mu;
  }
  for (const auto& row : particle_rows_)
    for (unsigned int l = 0; l < n_modes; ++l)
      beta[l] += row.r[l] * particles.displacement(row.index)[row.component];
  for (const auto& row : dof_rows_)
    for (unsigned int l = 0; l < n_modes; ++l)
      beta[l] += row.r[l] * u_fem[ghosted_lid_[row.index]];
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) > 1) {
    std::vector<double> sums(moment.begin(), moment.end());
    sums.insert(sums.end(), beta.begin(), beta.end());
    Utilities::MPI::sum(sums, comm, sums);
    std::copy(sums.begin(), sums.begin() + n_modes, moment.begin());
    std::copy(sums.begin() + n_modes, sums.end(), beta.begin());
  }
  Q_.vmult(alpha, moment);
}

template <int dim>
void EnergySplice<dim>::on_fem_forces(const StepForces& forces) {
  Assert(ready_, ExcMessage("EnergySplice::rebuild() before the first step"));
  auto& fem = state_.fem;
  const auto& particles = state_.particles;
  const auto& owned = fem.locally_owned_dofs();
  std::fill(splice_forces_.begin(), splice_forces_.end(), Vector());
  // The ghosts' reactions on every DoF: those that move (free or driven) and the prescribed
  // ones, whose reactions (and the supports' work in the energy account) they are part of.
  for (std::size_t k = 0; k < fem_reaction_values_.size(); ++k)
    if (fem_reaction_values_[k] != 0 &&
        (forces.is_free(k) || forces.is_driven(k) || forces.is_prescribed(k)))
      forces.add(k, fem_reaction_values_[k]);
  // The correction −C u = −R α − M A Q (β − S α), α = Pᵀu = Q Aᵀ M u, β = Rᵀu.
  const double* mass = fem.lumped_mass().begin();
  dealii::Vector<double> alpha(n_modes), beta(n_modes), gamma(n_modes), t(n_modes);
  correction_sums(alpha, beta);
  S_.vmult(t, alpha);
  correction_energy_ = beta * alpha - 0.5 * (alpha * t);
  t.sadd(-1.0, 1.0, beta); // β − S α
  Q_.vmult(gamma, t);
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i] && state_.is_owned(i))
      for (unsigned int d = 0; d < dim; ++d) {
        const auto a = modes(particles.reference_position(i), d);
        double f = 0;
        for (unsigned int l = 0; l < n_modes; ++l)
          f -= a[l] * gamma[l];
        splice_forces_[i][d] += particles.mass(i) * f; // on a fixed component: a reaction
      }
  for (const auto& row : particle_rows_) {
    double f = 0;
    for (unsigned int l = 0; l < n_modes; ++l)
      f -= row.r[l] * alpha[l];
    splice_forces_[row.index][row.component] += f;
  }
  {
    // On the free DoFs and, as reactions, on the prescribed ones.
    std::vector<double> f(owned.n_elements(), 0.0);
    for (const unsigned int k : row_dofs_) {
      const auto a = modes(dof_point_[k], dof_component_[k]);
      double g = 0;
      for (unsigned int l = 0; l < n_modes; ++l)
        g -= a[l] * gamma[l];
      f[k] = mass[k] * g;
    }
    for (const auto& row : dof_rows_)
      for (unsigned int l = 0; l < n_modes; ++l)
        f[row.index] -= row.r[l] * alpha[l];
    for (const unsigned int k : row_dofs_)
      forces.add(k, f[k]);
  }
  if (measure_) {
    // u^n and v^{n−½}: nothing has moved yet.
    measure_ = false;
    measured_stored_ = fem.linear_stored_energy() + correction_energy_ +
                       Utilities::MPI::sum(owned_particle_energy(), fem.mpi_communicator());
    measured_particle_v_ = particles.velocities();
    const double* v = fem.velocity().trilinos_vector()[0];
    measured_fem_v_.resize(owned.n_elements());
    for (std::size_t k = 0; k < owned.n_elements(); ++k)
      measured_fem_v_[k] = v[ghosted_lid_[k]];
  }
  // The net forces on the driven DoFs (FEM and reactions) to the particles: Φᵀ.
  for (const auto& entry : interface_.dofs()) {
    if (!owned.is_element(entry.dof))
      continue;
    const auto k = owned.index_within_set(entry.dof);
    if (!forces.is_driven(k))
      continue;
    const double F = forces.force(k);
    for (const auto& [p, phi] : entry.weights)
      splice_forces_[p][entry.component] += phi * F;
  }
  halo_.add_to_owners(splice_forces_); // stencil particles owned elsewhere
}

template <int dim>
double EnergySplice<dim>::energy() {
  auto& fem = state_.fem;
  const auto& particles = state_.particles;
  const double stored_fem = fem.linear_stored_energy();
  // This rank's share: kinetic energy of its free particles and particle energy of its rows,
  // less the kinetic energy of its interface DoFs (they follow the particles and carry no
  // inertia in this splice), which the FEM's kinetic energy below includes.
  double local = 0;
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i] && state_.is_owned(i))
      local += 0.5 * particles.mass(i) * particles.velocity(i).norm_square();
  const double* v = fem.velocity().trilinos_vector()[0]; // ghosted_lid_ order
  const double* mass = fem.lumped_mass().begin();
  const auto& owned = fem.locally_owned_dofs();
  for (const auto& entry : interface_.dofs())
    if (owned.is_element(entry.dof)) {
      const auto k = owned.index_within_set(entry.dof);
      const double vk = v[ghosted_lid_[k]];
      local -= 0.5 * mass[k] * vk * vk;
    }
  local += owned_particle_energy();
  const double shared = Utilities::MPI::sum(local, fem.mpi_communicator());
  const double kinetic_fem = fem.kinetic_energy();
  // ½ uᵀ C u at the current state.
  const double correction = current_correction_energy();
  return shared + kinetic_fem + stored_fem + correction;
}

template <int dim>
double EnergySplice<dim>::centred_energy() {
  const auto& particles = state_.particles;
  if (measured_particle_v_.size() != particles.size())
    return std::numeric_limits<double>::quiet_NaN();
  auto& fem = state_.fem;
  double kinetic = 0;
  for (unsigned int i = 0; i < particles.size(); ++i)
    if (state_.free[i] && state_.is_owned(i))
      kinetic += 0.125 * particles.mass(i) *
                 (particles.velocity(i) + measured_particle_v_[i]).norm_square();
  const double* v = fem.velocity().trilinos_vector()[0]; // ghosted_lid_ order
  const double* mass = fem.lumped_mass().begin();
  const auto& owned = fem.locally_owned_dofs();
  std::vector<std::uint8_t> interface(owned.n_elements(), 0);
  for (const auto& entry : interface_.dofs())
    if (owned.is_element(entry.dof))
      interface[owned.index_within_set(entry.dof)] = 1;
  for (std::size_t k = 0; k < owned.n_elements(); ++k)
    if (!interface[k]) {
      const double vc = 0.5 * (v[ghosted_lid_[k]] + measured_fem_v_[k]);
      kinetic += 0.5 * mass[k] * vc * vc;
    }
  measured_particle_v_.clear();
  return Utilities::MPI::sum(kinetic, fem.mpi_communicator()) + measured_stored_;
}

template <int dim>
std::size_t EnergySplice<dim>::memory_bytes() const {
  return (splice_forces_.capacity() + measured_particle_v_.capacity()) * sizeof(Vector) +
         particle_rows_.capacity() * sizeof(Row);
}

template class EnergySplice<2>;
template class EnergySplice<3>;

} // namespace spinesim::coupling
