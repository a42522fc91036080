#ifndef SPINESIM_COUPLING_COUPLING_STATE_H
#define SPINESIM_COUPLING_COUPLING_STATE_H

// What the pieces of the coupling share: the two models, the particle lattice made once from
// the FEM mesh, and the particle side (particles replicated on every rank, their host cells,
// owners and the bond rows owned here). The pieces (CellConverter, GhostLayer, BondRows,
// ParticleBoundary, MlsInterface, ParticleHalo, FractureHeat, CoupledIntegrator,
// CouplingCheckpoint) hold a reference to it; each keeps its own bookkeeping.

#include "coupling/coupling_parameters.h"

#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "meshfree/bond_list.h"
#include "meshfree/particle_method.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/lac/full_matrix.h>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::fem {
template <int dim>
class HeatSolver;
}

namespace spinesim::coupling {

// Wall time of the conversions by phase, summed over the run [s].
struct CouplingTimings {
  double criteria = 0;     // indicators on the candidate cells (flagged_cells)
  double records = 0;      // particles made from the cells, exchanged and added
  double deactivation = 0; // cells out of the FEM (stiffness, mass)
  double ghosts = 0;       // the ghost layer
  double bonds = 0;        // incremental bond search and row ownership
  double interface = 0;    // interface DoFs, their MLS fits, halo plan, first update
  double totals = 0;       // mass, momentum and energy before and after (the report)
  double snapshots = 0;    // states held and restored for step cuts (relax_step), not conversion
};

template <int dim>
struct CouplingState {
  using DoFCell = typename dealii::DoFHandler<dim>::active_cell_iterator;
  // A locally owned host cell and its particle per point (-1 where none).
  using HostRow = std::pair<DoFCell, std::vector<int>>;

  // Checks that the solver runs what the coupling supports (explicit or quasi-static, small
  // strain, Q1).
  CouplingState(const CouplingParameters<dim>& parameters, fem::MechanicsSolver<dim>& mechanics,
                const fem::HeatSolver<dim>* heat);

  // Material, lattice spacing, shape table and particle method, from the FEM (once).
  void prepare();
  // A cell of the unconverted material ids (an implant's): it never converts, its nodes are
  // never driven by the particles, and the particles meet it through the bonds to its ghosts,
  // whose forces its FEM takes back (ImplantJoint).
  bool never_converts(const DoFCell& cell) const {
    for (const unsigned int id : prm.unconverted_material_ids)
      if (cell->material_id() == id)
        return true;
    return false;
  }
  // Per particle: 1 if its host cell is of an unconverted material id (a ghost in an
  // implant), on every rank (the host cells' owners decide; one reduction). Collective.
  std::vector<std::uint8_t> in_unconverted_cells() const;
  // Appends a particle hosted by point `point` of cell `cell_id`: a ghost, no fixed slots.
  unsigned int add_particle(const std::string& cell_id, unsigned int point,
                            const dealii::Point<dim>& position, double volume);
  // Empties the particle side (a checkpoint replaces it).
  void clear_particles();
  // Whether the particle method continues the constitutive state of the cells.
  bool carries_state() const { return method && method->carries_material_state(); }
  // The committed constitutive state of a locally owned cell at its particle point `point`:
  // the state of the nearest quadrature point (a transferred state stays admissible, on or
  // inside the yield surface; interpolated states need not). MechanicsSolver::refresh_states()
  // first.
  materials::MaterialState cell_state(const DoFCell& cell, unsigned int point) const;
  // Finite strain: the point's deformation gradient at the current displacement as the law
  // sees it (F̄ with F-bar, 3 × 3), which the FEM's next update would take; none for small
  // strain or an inverted cell (meshfree::CarriedState).
  std::optional<materials::Tensor2> cell_state_deformation(const DoFCell& cell,
                                                           unsigned int point) const;
  // A carried state for particle i from the record's state (pending_states).
  template <class Record>
  static meshfree::CarriedState carried(unsigned int i, const Record& r) {
    meshfree::CarriedState c;
    c.particle = i;
    c.state = r.state;
    if (r.has_state_deformation)
      c.deformation = r.state_deformation;
    return c;
  }

  bool is_owned(unsigned int i) const {
    return owner.empty() || owner[i] == static_cast<int>(rank);
  }
  unsigned int n_free_particles() const;
  unsigned int n_ghost_particles() const;
  double horizon() const;
  // Bytes of particle data held on this rank: the particle records (all of them, replicated on
  // every rank), their bookkeeping, the bonds owned here and the method's per-particle arrays.
  std::size_t memory_bytes() const;

  const CouplingParameters<dim> prm;
  fem::MechanicsSolver<dim>& fem;
  const fem::HeatSolver<dim>* heat; // optional
  unsigned int rank = 0;

  // The lattice, made by prepare().
  dealii::QIterated<dim> points;              // particle points of a cell (unit cell)
  dealii::FullMatrix<double> shape;           // N_i(ξ_q), [q][i]
  std::map<std::string, DoFCell> owned_cells; // locally owned cells by CellId
  std::vector<DoFCell> owned_by_index; // locally owned cells by active cell index (else invalid)
  // The owned cells of the particle lattice's size, by active index: only these can convert
  // (the refinement box makes them).
  std::vector<DoFCell> lattice_cells;
  // E, ν and ρ of the law the method is constructed with (a lattice cell's, the same on
  // every rank); the particles run their own laws from `laws`.
  double spacing = 0, youngs = 0, poisson = 0, density = 0;
  // The particles' laws (ParticleSet::material_id indexes them), shared with the method, and
  // their parameters in the same order: records name their host cell's law by its
  // parameters, so every rank, adding records in the all-gathered order, gives a law the
  // same index; a checkpoint writes them.
  std::shared_ptr<meshfree::MaterialTable> laws = std::make_shared<meshfree::MaterialTable>();
  std::vector<materials::LawParameters> law_parameters;
  // The index of the law `p` describes, added to `laws` if new. `local`: this rank's object
  // for that law (a cell's), shared with the FEM; null builds it from `p`.
  unsigned int law_index(const materials::LawParameters& p,
                         std::shared_ptr<const materials::ConstitutiveLaw> local = nullptr);
  // The parameters of `cell`'s law; InvalidInput naming the law if it cannot give them.
  materials::LawParameters cell_law_parameters(const DoFCell& cell) const;
  // This rank's law object of cell `cell_id` if it owns the cell, else null.
  std::shared_ptr<const materials::ConstitutiveLaw> owned_law(const std::string& cell_id) const;
  // Empties `laws` (a checkpoint brings its own).
  void clear_laws();
  std::unique_ptr<meshfree::ParticleMethod<dim>> method;
  // What `method` was made for (EnergySplice makes a second one for its probes).
  meshfree::ParticleMaterial particle_material;
  // Per particle point of a cell: the nearest quadrature point of the FEM (cell_state()).
  std::vector<unsigned int> nearest_quadrature_point;
  // States carried into particles since the last rebuild of the layers (conversions, new
  // ghosts): BondRows::hand_over_states gives them to the method once its families exist and
  // the particles' displacements are current.
  std::vector<meshfree::CarriedState> pending_states;
  // For the run log (FemParticleCoupling::take_messages).
  std::vector<std::string> messages;

  // The particles, replicated on every rank; indices never change (only appended; a
  // checkpoint replaces them all).
  meshfree::ParticleSet<dim> particles;
  std::vector<std::uint8_t> free; // 1 free, 0 ghost (driven by the FEM)
  // Per particle: the FEM's deformation gradient I + ∇u at a ghost (GhostLayer::update; the
  // halo brings those owned elsewhere), identity for free particles. The method reads it when
  // ghost_gradients_from_fem() (ParticleMethod::set_driven_gradients).
  std::vector<dealii::Tensor<2, dim>> driven_gradients;
  // Ghost rows that take driven_gradients (BondRows: all ghosts with Ghost gradient = fem, those
  // whose family reaches another law with auto), on this rank.
  unsigned int ghosts_at_fem_gradient = 0;
  bool ghost_gradients_from_fem() const {
    return prm.splice == "overlap" &&
           (prm.ghost_gradient == "fem" ||
            (prm.ghost_gradient == "auto" && prm.particles_method == "nosb"));
  }
  std::vector<std::string> host_cell;   // CellId of the cell the particle sits in
  std::vector<unsigned int> host_point; // index of the point within that cell
  // Per particle: the active cell index of its host cell if this rank owns it, else -1 (the
  // CellId strings need a map lookup).
  std::vector<int> host_index;
  std::map<std::pair<std::string, unsigned int>, unsigned int> index_of; // (cell, point) -> i
  std::map<std::string, unsigned int> law_lookup; // law_key(parameters) -> index in `laws`
  std::vector<std::uint32_t> fixed_slots;         // per particle: Dirichlet slots of its cell
  // Per particle: its fixed components' offset from the prescribed values [m]
  // (ParticleRecord::support_offset).
  std::vector<dealii::Tensor<1, dim>> support_offset;
  // Rank owning each particle's host cell (empty on one rank: all owned); ParticleHalo::plan.
  std::vector<int> owner;
  // Owned host cells of free particles in ascending active index (temperatures, fracture
  // heat); rebuilt with the ghost layer.
  std::vector<HostRow> free_cells;
  // Bonds of the free particles owned here (BondRows).
  meshfree::BondList<dim> bonds;

  CouplingTimings timings;
};

} // namespace spinesim::coupling

#endif
