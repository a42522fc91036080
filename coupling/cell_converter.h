#ifndef SPINESIM_COUPLING_CELL_CONVERTER_H
#define SPINESIM_COUPLING_CELL_CONVERTER_H

// Cells -> particles. A flagged cell leaves the FEM system (MechanicsSolver::set_active_cells,
// no remeshing) and becomes n^dim particles at the points of the iterated midpoint rule
// (sub-cell centres: on a uniform mesh the regular lattice PD is calibrated on). Each particle
// inherits u, v and T interpolated from the cell; the particle masses add up to the mass the
// cell removes from the lumped FEM mass; the velocities are the cell's mean velocity plus the
// interpolated fluctuation about it, scaled so that they carry the kinetic energy the nodes
// lose. Mass, linear momentum and kinetic energy are conserved to round-off (kinetic energy
// only with more than one particle per cell; the defect is reported). Points inside
// Coupling/Hole make no particle; what they carried is reported apart.

#include "coupling/coupling_state.h"
#include "coupling/particle_record.h"

#include <deal.II/base/tensor.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/grid/cell_id.h>

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace spinesim::coupling {

template <int dim>
struct ConversionReport {
  unsigned int cells = 0, particles = 0;
  double mass_before = 0, mass_after = 0;                 // [kg]
  dealii::Tensor<1, dim> momentum_before, momentum_after; // [kg m/s]
  double kinetic_before = 0, kinetic_after = 0;           // [J]
  double max_velocity_scale = 1; // largest λ on the velocity fluctuation of a cell [-]
  // What the points inside Coupling/Hole took away with their cells: the FEM carried material
  // there that the body does not have. The changes below are measured net of it.
  double hole_mass = 0;                 // [kg] (2-D: per unit thickness, kg/m)
  dealii::Tensor<1, dim> hole_momentum; // [kg m/s]
  double hole_kinetic = 0;              // [J]
  // Methods that carry material state: ∫ ε̄_p dV over the cells (their quadrature) and
  // Σ V_i ε̄_p,i over their particles [m^3]; equal when every state arrived (nearest quadrature
  // point, n = 2 particles per direction on Q1 with 2 × 2 Gauss: one particle per point).
  bool carries_state = false;
  double plastic_strain_before = 0, plastic_strain_after = 0;
  // Quasi-static: ‖reactions‖ at the equilibrium before the conversion and at the next one,
  // under the same load [N] (CoupledIntegrator::relax); 0 when not measured.
  double reaction_before = 0, reaction_after = 0;
  // With the energy account on (explicit runs): the U + K this conversion added to the
  // particles and to the FEM (negative: lost), at the state it happened in [J] (2-D: J/m).
  // The FEM's U is ½ uᵀ K u on the linear path; on the internal-work path a conversion does not
  // change what the account holds for the FEM, so only its kinetic energy counts.
  double energy_change_particles = 0, energy_change_fem = 0;
  double plastic_strain_change_relative() const; // over ∫ ε̄_p dV (absolute if that is 0)
  double reaction_jump_relative() const;
  double mass_change_relative() const;
  double kinetic_change_relative() const;  // over the kinetic energy before
  double momentum_change_relative() const; // over |p| (or over mass × max speed if p ≈ 0)
  // One run-log line: what moved and what it conserved ("4 cells -> 32 particles (mass change
  // ...)"); `force_unit` names the reactions' unit (" N", or " N/m" in 2-D).
  std::string describe(const char* force_unit) const;
};

template <int dim>
class CellConverter {
 public:
  // `rebuild_layers` rebuilds the ghost layer, bonds and interface after cells converted.
  CellConverter(CouplingState<dim>& state, std::function<void()> rebuild_layers)
      : state_(state), rebuild_layers_(std::move(rebuild_layers)) {}

  // Local refinement of the refinement box; with All particles, uniform refinement to the
  // finest level so that every particle has the same spacing. Before any solver setup.
  static void prepare_mesh(const CouplingParameters<dim>& parameters,
                           dealii::parallel::distributed::Triangulation<dim>& triangulation);

  // The initial region (or every cell with All particles), as CellIds on every rank.
  std::vector<dealii::CellId> initial_cells() const;
  // Cells flagged by the criteria (plus the buffer around them), as CellIds on every rank.
  std::vector<dealii::CellId> flagged_cells() const;
  // Converts these cells (ids common to all ranks; already converted ones are skipped).
  ConversionReport<dim> convert(const std::vector<dealii::CellId>& cells);
  // Checks the criteria and converts; cells = 0 if nothing converted.
  ConversionReport<dim> convert_flagged();

  // The energy splice's conserved energy (EnergySplice::energy, collective): the account then
  // books the jump of that energy across a conversion (as energy_change_particles; the FEM's
  // share is in it) instead of the two models' stored and kinetic energies.
  void set_splice_energy(std::function<double()> energy) { splice_energy_ = std::move(energy); }

  // CellId -> conversion batch.
  const std::map<std::string, unsigned int>& converted() const { return converted_; }
  // From a checkpoint: these cells are converted, and out of the FEM.
  void restore(std::map<std::string, unsigned int> converted);
  const std::vector<ConversionReport<dim>>& reports() const { return reports_; }
  // Conversions undone (a cut step restored the state before them): only the first n reports
  // stay.
  void keep_reports(std::size_t n) {
    if (n < reports_.size())
      reports_.resize(n);
  }
  // Sums of energy_change_particles and energy_change_fem over the conversions so far [J].
  double energy_change_particles() const;
  double energy_change_fem() const;
  // From a checkpoint: the sums of the conversions before it (the reports are not kept).
  void restore_energy_changes(double particles, double fem) {
    restored_energy_particles_ = particles;
    restored_energy_fem_ = fem;
  }
  // The latest report, for measures taken after the conversion (CoupledIntegrator::relax).
  ConversionReport<dim>& last_report() { return reports_.back(); }

 private:
  // The particles of the cells in `todo` this rank owns, with u, v, T from the FEM, masses
  // and kinetic energy matched to what the nodes lose; raises max_velocity_scale to the
  // largest λ used.
  using DoFCell = typename CouplingState<dim>::DoFCell;
  // Whether the criteria may convert this cell (Conversion region; everywhere when unset).
  bool in_conversion_region(const DoFCell& cell) const;
  // The points the mechanics' Dirichlet conditions hold, over all ranks, for Coupling/Support
  // clearance: centres and vertices of the faces on a support's boundary id, and the vertices
  // inside a support's region. Collective on the first call (every rank checks the criteria
  // at the same time), cached after it.
  const std::vector<dealii::Point<dim>>& support_points() const;
  // The mass, momentum and kinetic energy of points inside the hole go into `hole` (as its
  // *_before members, this rank's share).
  std::vector<ParticleRecord<dim>> make_records(const std::set<std::string>& todo,
                                                double& max_velocity_scale,
                                                ConversionReport<dim>& hole) const;

  CouplingState<dim>& state_;
  std::function<void()> rebuild_layers_;
  std::function<double()> splice_energy_;
  std::map<std::string, unsigned int> converted_;
  mutable std::optional<std::vector<dealii::Point<dim>>> support_points_;
  std::vector<ConversionReport<dim>> reports_;
  double restored_energy_particles_ = 0, restored_energy_fem_ = 0; // [J]
};

} // namespace spinesim::coupling

#endif
