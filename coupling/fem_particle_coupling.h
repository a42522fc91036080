#ifndef SPINESIM_COUPLING_FEM_PARTICLE_COUPLING_H
#define SPINESIM_COUPLING_FEM_PARTICLE_COUPLING_H

// The FEM bulk and a particle fracture zone (meshfree/particle_method.h) in one run: explicit
// dynamics, or quasi-static steps by adaptive dynamic relaxation of both models together.
//
// Conversion: a flagged cell leaves the FEM system (MechanicsSolver::set_active_cells, no
// remeshing) and becomes n^dim particles at the points of the iterated midpoint rule (sub-cell
// centres: on a uniform mesh they form the regular lattice PD is calibrated on). Each particle
// inherits u, v and T interpolated from the cell; the particle masses are scaled so that they
// add up to the mass the cell removes from the lumped FEM mass; the particle velocities are the
// cell's mean velocity (the momentum its nodes lose over their mass) plus the interpolated
// fluctuation about it, scaled so that they carry the kinetic energy the nodes lose. Mass,
// linear momentum and kinetic energy are therefore conserved to round-off (kinetic energy
// only with more than one particle per cell: a single particle has no fluctuation to scale,
// and the defect is logged).
//
// Interface (why this method): an overlapping Dirichlet–Dirichlet splice. Active cells within a
// ghost layer (at least 2 horizons) of the free particles carry ghost particles on the same
// lattice, driven by the FEM displacement; FEM DoFs shared by active and converted cells are
// driven by a linear moving-least-squares fit of the free particles. Every free DoF on either
// side then sees a complete neighbourhood of its own model (a full horizon, full element
// patches), so any affine field is reproduced exactly and creates no force: the patch test
// holds to round-off with no ghost forces, which energy-blended couplings of bond-based PD and
// FEM cannot offer. The price is that the coupled operator is not symmetric (no exact energy
// statement); the wave test measures the reflection this costs. Explicit steps use one common
// stable step (the smaller of the FEM CFL and the PD bound).
//
// MPI: the FEM side is distributed by p4est, and every particle is owned by the rank owning
// its host cell: only that rank holds its bond row, computes its force, advances it (free) or
// interpolates it from the FEM (ghost). The particle records (positions, volumes, flags) are
// replicated, so conversions and the neighbour search see every particle; the states of
// the particles a rank reads but does not own (bond partners, MLS stencils of its interface
// nodes) arrive by a halo exchange with their owners after every update, and synchronise()
// brings every state to every rank for output, checkpoints and figures.

#include "fem/mechanics_solver.h"
#include "meshfree/bond_list.h"
#include "meshfree/particle_method.h"
#include "meshfree/particle_set.h"
#include "meshfree/pre_crack.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/grid/cell_id.h>
#include <deal.II/lac/vector.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::fem {
template <int dim>
class HeatSolver;
}

namespace spinesim::coupling {

template <int dim>
class FemParticleCoupling {
 public:
  struct Parameters {
    unsigned int particles_per_direction = 1; // particles per cell = this^dim
    double ghost_layer = 2.0;                 // ghost layer width [horizons]
    double interface_radius = 2.5;            // MLS support of interface nodes [spacings]
    double time_step_safety = 0.8;            // PD stable step factor [-]
    bool all_particles = false;
    std::vector<double> region_lower, region_upper; // particles from t = 0 (empty = none)
    double principal_strain_threshold = 0;          // [-], 0 = off
    double plastic_strain_threshold = 0;            // [-], 0 = off
    double min_jacobian_ratio = 0;                  // [-], 0 = off
    double min_time_step = 0;                       // [s], 0 = off
    double buffer = 0;                              // converted around flagged cells [m]
    unsigned int check_interval = 10;               // steps between conversion checks
    bool damage = true;                             // bonds may break (Effects/Damage)
    std::vector<double> refine_lower, refine_upper; // box refined before the run [m]
    unsigned int region_refinements = 0;
    double fracture_heat_fraction = 1.0; // share of broken-bond energy returned as heat [-]
    bool conserve_kinetic_energy = true; // scale the velocity fluctuation at conversion
    double relaxation_tolerance = 1e-6;  // quasi-static: free residual / reaction scale [-]
    unsigned int relaxation_max_iterations = 200000; // quasi-static: per step [-]
    // The particle method (Effects/Particles method), its parameters read from its subsection
    // of "Coupling"; made in prepare() with the material of the FEM cells.
    std::string particles_method = "bond_based";
    meshfree::ParticleMethodMaker<dim> make_method;
    std::vector<std::vector<double>> cracks; // flattened corners per pre-crack [m]

    static void declare(dealii::ParameterHandler& prm);
    // `particles_method` is the registered name the scene chose (Effects/Particles method).
    void parse(dealii::ParameterHandler& prm, const std::string& particles_method);
  };

  struct ConversionReport {
    unsigned int cells = 0, particles = 0;
    double mass_before = 0, mass_after = 0;                 // [kg]
    dealii::Tensor<1, dim> momentum_before, momentum_after; // [kg m/s]
    double kinetic_before = 0, kinetic_after = 0;           // [J]
    double max_velocity_scale = 1; // largest λ on the velocity fluctuation of a cell [-]
    double mass_change_relative() const;
    double kinetic_change_relative() const;  // over the kinetic energy before
    double momentum_change_relative() const; // over |p| (or over mass × max speed if p ≈ 0)
  };

  // Local refinement of the refinement box; with All particles, uniform refinement to the
  // finest level so that every particle has the same spacing. Call before any solver setup.
  static void prepare_mesh(const Parameters& parameters,
                           dealii::parallel::distributed::Triangulation<dim>& triangulation);

  // The solver must be set up, explicit, small strain, one law (E, ν, ρ from the first active
  // cell's law: the PD micromodulus is calibrated to it). `heat` is optional.
  FemParticleCoupling(const Parameters& parameters, fem::MechanicsSolver<dim>& mechanics,
                      const fem::HeatSolver<dim>* heat = nullptr);
  ~FemParticleCoupling();

  // Converts the initial region (or every cell with All particles) and builds the interface.
  void initialise();

  // Cells flagged by the criteria (plus the buffer around them), as CellIds on every rank.
  std::vector<dealii::CellId> flagged_cells() const;
  // Converts these cells (ids common to all ranks; already converted ones are skipped).
  ConversionReport convert(const std::vector<dealii::CellId>& cells);
  // Checks the criteria and converts; returns the report (cells = 0 if nothing converted).
  ConversionReport convert_flagged();

  // After the FEM state was replaced (MechanicsSolver::set_state): ghosts and interface DoFs
  // follow it again.
  void refresh();

  double stable_time_step() const; // min(FEM CFL step, PD step) [s]
  // One central-difference step of both models (see the .cc for the order).
  void step(double dt);

  // Quasi-static: adaptive dynamic relaxation of both models to equilibrium under the loads of
  // `time` (see the .cc); bonds break on the way and, with `with_conversion`, the cells
  // flagged at equilibrium convert and the state relaxes again, until none is flagged. Ends
  // with zero velocities. Not converged within Relaxation max iterations (all relaxations of
  // the step together): converged = false (the caller decides).
  struct RelaxationReport {
    bool converged = false;
    unsigned int iterations = 0;
    double relative_residual = 0; // at the end [-]
    double damping = 0;           // last adaptive damping [1/s]
    std::vector<ConversionReport> conversions;
  };
  RelaxationReport relax(double time, bool with_conversion);

  // Sets every free DoF and free particle to the affine field u = H x (for the patch test).
  void impose_affine(const dealii::Tensor<2, dim>& H);
  // Internal forces at the current state without advancing: max |f| over free particles and
  // over free FEM DoFs (neither Dirichlet nor driven) [N].
  std::pair<double, double> max_free_forces();

  // Totals over both models (FEM lumped mass, particle masses) [kg], [kg m/s], [J].
  double total_mass() const;
  dealii::Tensor<1, dim> total_momentum() const;
  double kinetic_energy() const;
  double strain_energy() const; // FEM + PD (bonds of free particles) [J]
  // Reaction on a boundary id: FEM reaction + fixed particles of converted boundary cells [N].
  dealii::Tensor<1, dim> reaction_force(dealii::types::boundary_id id) const;

  // Particle heat sources for the FEM heat equation: the energy of the bonds broken since the
  // last call (× Fracture heat fraction) as a power density [W/m^3] over `elapsed` [s], one
  // entry per active cell (locally owned host cells of free particles; others 0). Tracked only
  // when the coupling has a heat solver.
  dealii::Vector<double> take_fracture_heat(double elapsed);
  double fracture_dissipation() const; // energy of all broken bonds so far [J], collective
  double fracture_heat() const { return fracture_heat_; } // handed to the FEM so far [J]

  unsigned int n_free_particles() const;
  unsigned int n_ghost_particles() const;
  unsigned int n_converted_cells() const { return static_cast<unsigned int>(converted_.size()); }
  std::size_t n_broken_bonds() const;
  double max_damage() const;
  double particle_spacing() const { return spacing_; }
  double horizon() const;
  const meshfree::ParticleSet<dim>& particles() const { return particles_; }
  bool is_free(unsigned int i) const { return free_[i] != 0; }
  const std::vector<ConversionReport>& conversions() const { return reports_; }

  // Wall time of the conversions by phase, summed over the run [s].
  struct Timings {
    double criteria = 0;     // indicators on the candidate cells (flagged_cells)
    double records = 0;      // particles made from the cells, exchanged and added
    double deactivation = 0; // cells out of the FEM (stiffness, mass)
    double ghosts = 0;       // the ghost layer
    double bonds = 0;        // incremental bond search and row ownership
    double interface = 0;    // interface DoFs, their MLS fits, halo plan, first update
    double totals = 0;       // mass, momentum and energy before and after (the report)
  };
  const Timings& timings() const { return timings_; }

  // Every rank's copy of u, v, damage and temperature of all particles from their owners
  // (collective; output, checkpoints and figures read the replicated set).
  void synchronise() const;
  bool is_owned(unsigned int i) const {
    return owner_.empty() || owner_[i] == static_cast<int>(rank_);
  }

  // particles_<cycle>.vtu of the free particles (rank 0); returns the file name. Collective.
  std::string write_output(const std::string& directory, unsigned int cycle) const;
  void save(const std::string& file) const; // rank 0 writes
  void load(const std::string& file);       // every rank reads; FEM state restored separately

 private:
  struct Impl;
  Parameters prm_;
  fem::MechanicsSolver<dim>& fem_;
  const fem::HeatSolver<dim>* heat_;
  std::unique_ptr<Impl> impl_;

  meshfree::ParticleSet<dim> particles_;
  meshfree::BondList<dim> bonds_;
  std::unique_ptr<meshfree::ParticleMethod<dim>> method_; // made by prepare()
  std::vector<std::uint8_t> free_;                        // 1 free, 0 ghost (driven by the FEM)
  std::vector<std::string> host_cell_;                    // CellId of the cell the particle sits in
  std::vector<unsigned int> host_point_;                  // index of the point within that cell
  std::map<std::pair<std::string, unsigned int>, unsigned int> index_of_;
  std::map<std::string, unsigned int> converted_; // CellId -> conversion batch
  std::vector<ConversionReport> reports_;
  double spacing_ = 0, youngs_ = 0, poisson_ = 0, density_ = 0;
  double time_ = 0;
  std::vector<double> fracture_energy_; // per particle, not yet handed to the FEM [J]
  double fracture_dissipation_ = 0;     // of the rows owned here [J]
  double fracture_heat_ = 0;            // global [J]

  void prepare(); // material, lattice spacing, shape table, PD model (once)
  void rebuild_interface();
  void rebuild_bonds();
  // Appends the host cell and point of a particle just added (and its owned-cell index).
  void add_host(const std::string& cell_id, unsigned int point);
  void update_ghosts();
  void update_interface_dofs();
  void apply_particle_dirichlet(double time, double dt);
  using RelaxationSums = typename fem::MechanicsSolver<dim>::RelaxationSums;
  // One central-difference step of both models with damping a [1/s] and the loads of
  // load_time; with `sums`, a relaxation step (the time is held) that adds up the free
  // residual, reactions and stiffness estimate of this rank.
  void advance(double dt, double a, double load_time, bool first, RelaxationSums* sums);
  // Owners and the halo plan: which particles this rank reads but others own, and which of its
  // own the others read.
  void plan_exchange();
  void exchange_halo();    // u, v of halo particles from their owners
  std::vector<int> owner_; // rank owning each particle's host cell
  mutable Timings timings_;
  unsigned int rank_ = 0;
};

} // namespace spinesim::coupling

#endif
