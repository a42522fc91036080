#ifndef SPINESIM_MESHFREE_PARTICLE_METHOD_H
#define SPINESIM_MESHFREE_PARTICLE_METHOD_H

// One interface for the particle methods (bond-based PD, NOSB-PD, SPG, ...): what a
// stand-alone particle zone or a coupled FEM/particle run needs from a method, so the runs
// never name a method. Each method implements it in its own file pair and registers itself
// by name (SPINESIM_REGISTER_PARTICLE_METHOD below); `Effects/Particles method` takes its
// allowed values and their help text from this registry.
//
// Conventions (meshfree/particle_set.h): particles.force() is the internal force [N];
// volumes carry the 2-D thickness. The bond list is built by the caller with the method's
// neighbor_options() and belongs to the particles: methods read it, break bonds in it and
// never reorder it.
//
// Material history: compute_forces() evaluates the constitutive law from the last committed
// state and keeps the new one as a trial state; commit_state() accepts it (explicit dynamics:
// after every step; quasi-static: once the step has converged), rollback_state() discards it
// (a step that is cut and retried).

#include "base/registry.h"
#include "fem/materials/constitutive_law.h"
#include "meshfree/bond_list.h"
#include "meshfree/material_table.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_set.h"
#include "meshfree/short_range_forces.h"

#include <deal.II/base/parameter_handler.h>

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

// The material a method is calibrated to. E and ν calibrate micromoduli (bond-based PD);
// `law` is the point-wise constitutive law of fem/materials (NOSB-PD, SPG).
struct ParticleMaterial {
  double youngs_modulus = 0; // E [Pa]
  double poisson_ratio = 0;  // ν [-]
  double density = 0;        // ρ [kg/m^3]
  std::shared_ptr<const materials::ConstitutiveLaw> law;
  // Temperature at which the particles are free of thermal strain [K]: the law sees
  // particles.temperature() minus this (a coupled run's particles carry absolute FEM
  // temperatures; stand-alone zones carry temperature changes and leave it 0). NaN: the
  // particles take no thermal strain (a coupled run whose FEM has none, though the heat
  // equation runs and the law has an expansion coefficient).
  double reference_temperature = 0;
  // Several materials (coupled runs): particle i runs law (*table)[material_id(i)] and `law`
  // is only a default for the method's construction. Null: every particle runs `law`. The
  // table may grow between initialise() calls (the method rereads it there).
  std::shared_ptr<const MaterialTable> table;
};

// One entry of a method's committed material history, keyed so that it survives a
// re-initialisation and can be written to a checkpoint: the family centred on `particle`
// (`neighbour` is the bond partner of a bond-associated family, `particle` itself for the
// particle's own family).
struct HistoryRecord {
  unsigned int particle = 0, neighbour = 0;
  materials::MaterialState state;
};

// A constitutive state carried into particle `particle` from elsewhere (the nearest quadrature
// point of a converted FEM cell), with that point's deformation gradient at the current
// displacement (3 × 3; none where the source is small-strain: its state is not tied to an F).
// A method that evaluates the law at its own F continues it through ConstitutiveLaw::
// transferred_state, so its next update starts from the elastic trial the source's would
// (an F-bar cell's F̄ against a family's F).
struct CarriedState {
  unsigned int particle = 0;
  materials::MaterialState state;
  std::optional<materials::Tensor2> deformation;
};

template <int dim>
class ParticleMethod {
 public:
  virtual ~ParticleMethod() = default;

  // The registered name (e.g. "bond_based").
  virtual std::string name() const = 0;
  // Whether particles carry the constitutive state (stress, plastic strain, hardening) of
  // the law; bond-based PD does not.
  virtual bool carries_material_state() const = 0;
  // Whether the method runs ParticleMaterial::table (a law per particle); one that does not
  // is refused in runs whose particles hold more than one law.
  virtual bool supports_material_table() const { return false; }
  // Out-of-plane thickness of a 2-D body the method was set up for [m] (1 in 3-D): particle
  // sets for it are made with this thickness.
  virtual double thickness() const = 0;
  // 2-D kinematic assumption of the method: plane stress (true) or plane strain.
  virtual bool plane_stress() const { return false; }
  // The Poisson ratio the method represents whatever the material says (bond-based PD's
  // Cauchy relation), or none when it follows the material.
  virtual std::optional<double> implied_poisson_ratio() const { return std::nullopt; }
  // Whether the force on a particle also needs the bond rows (families, integration points)
  // of its neighbours, as in NOSB-PD and SPG: a coupled run then keeps rows for the driven
  // particles within a horizon of the free ones.
  virtual bool needs_neighbour_rows() const { return false; }
  // Whether the forces are the negative gradient of strain_energy() (not so with SPG's
  // smoothing refreshed every n > 1 steps): energy accounts that correct the work of forces a
  // break removes rely on it.
  virtual bool forces_derive_from_energy() const { return false; }
  // Particles whose motion is prescribed from outside (the ghosts of a coupled run): a bond
  // between two of them never breaks. Empty = none. Call before initialise().
  virtual void set_driven(std::vector<std::uint8_t> driven) { (void)driven; }
  // Deformation gradients of driven particles from the model that drives them (the FEM's
  // displacement gradient at a coupling ghost), indexed by particle, and which particles take
  // theirs (`which[i]` = 1). A method whose stress comes from a family's gradient then
  // evaluates such a particle's family at this gradient instead of its own, so a ghost carries
  // the driving model's stress even where its family straddles a change of material. The
  // vector is owned by the caller and read at every force pass. nullptr (default): every family
  // uses its own gradient.
  virtual void set_driven_gradients(const std::vector<dealii::Tensor<2, dim>>* gradients,
                                    std::vector<std::uint8_t> which) {
    (void)gradients;
    (void)which;
  }
  // Particles [first, size) are ghosts of a distributed zone: copies of other ranks' particles
  // that the exchange moves, held so that the rows of the owned ones are whole. Their forces
  // are not used; a ghost without a bond row has no family by design, and a ghost's failure is
  // its owner's to report. Default: no ghosts. Call before initialise().
  virtual void set_first_ghost(unsigned int first) { (void)first; }

  // Neighbour requirements for a particle spacing h: search radius (horizon or support),
  // influence function, partial volumes, surface correction.
  virtual typename NeighborSearch<dim>::Options neighbor_options(double spacing) const = 0;
  // Per-particle data for these particles and bonds (families, bond constants, history).
  // Call again after particles were added or bonds changed from outside.
  virtual void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) = 0;

  // Internal forces into particles.force() [N] at the current displacements; with
  // `allow_breaking`, bonds past the method's failure criterion break first. Returns the
  // number of bond ends broken in this call (each pair counts twice). NumericalFailure naming
  // the particle on a non-finite force or an inverted deformation.
  virtual std::size_t compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                     bool allow_breaking) = 0;

  // The forces of this step before its breaks (an energy account's extra pass): like
  // compute_forces(..., false), but it is not a step of its own for the method's counters
  // (SPG's smoothing and kernel-reset cadence), so the step's breaking pass follows. Meant for
  // total Lagrangian SPG kernels (the only ones zones and coupled runs take): an updated
  // kernel would reset its reference in the step's own pass, after this one.
  virtual void compute_forces_before_breaks(ParticleSet<dim>& particles, BondList<dim>& bonds) {
    compute_forces(particles, bonds, false);
  }

  // S_i: a bound of particle i's stiffness row per volume [N/m^4] (the fictitious density of
  // adaptive dynamic relaxation, Kilic & Madenci 2010).
  virtual std::vector<double> stiffness_bound(const ParticleSet<dim>& particles,
                                              const BondList<dim>& bonds) = 0;
  // Stable explicit step times `safety` [s] (infinity for a particle with no bond).
  virtual double stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                  double safety) = 0;

  // Stored energy density W_i per particle [J/m^3] and the total Σ W_i V_i [J] (the total over
  // the particles before the first ghost, set_first_ghost()).
  virtual std::vector<double> strain_energy_density(const ParticleSet<dim>& particles,
                                                    const BondList<dim>& bonds) const = 0;
  virtual double strain_energy(const ParticleSet<dim>& particles,
                               const BondList<dim>& bonds) const = 0;
  // The energy bond k of particle i holds now [J]: what breaking it dissipates. Asked right
  // after the force pass that broke it, with `broken_before` the bonds' broken flags before
  // that pass (nullptr: bonds.broken): a bond broken in that pass still holds its energy, and
  // methods that share a particle's energy among its bonds share it among the bonds intact
  // before the pass.
  virtual double bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                             unsigned int i, std::size_t k,
                             const std::vector<std::uint8_t>* broken_before = nullptr) const = 0;
  // Damage φ_i ∈ [0, 1] into particles.damage().
  virtual void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const = 0;

  // Failure criteria the user switched on for this method (e.g. "Critical stretch = 0.01"),
  // empty when breaking follows only from the fracture energy or is off: a scene with
  // Effects/Damage = false names them in its log as not applied.
  virtual std::string user_failure_criteria() const { return {}; }

  // For a probe of the intact material (coupling/energy_splice.h): from now on no bond breaks,
  // whatever the failure criteria, and compute_forces(..., false) is no error.
  virtual void disable_breaking() {}

  virtual void commit_state() {}
  virtual void rollback_state() {}
  // The committed material history of the families centred on the particles with
  // which[i] != 0 (all when `which` is empty); nothing for a method without history.
  virtual std::vector<HistoryRecord> history(const std::vector<std::uint8_t>& which) const {
    (void)which;
    return {};
  }
  // Sets committed history by key (after initialise()); records of families this method
  // does not hold are skipped.
  virtual void set_history(const std::vector<HistoryRecord>& records) { (void)records; }
  // Sets the committed history of every family centred on each given particle (state carried
  // in from a converted FEM cell), at the particles' current displacements (they give each
  // family's F; after initialise()).
  virtual void set_particle_states(const ParticleSet<dim>& particles,
                                   const std::vector<CarriedState>& states) {
    (void)particles;
    (void)states;
  }
  // Particle i's committed state for output: its own family's, or the weighted mean over its
  // bond-associated families. The default state for a method without history.
  // The deformation gradient particle i's law sees at the last force evaluation (NOSB: its
  // particle family's F; SPG: its smoothed gradient), for stress output; nullopt for a method
  // without one, or a particle that carries no stress (a failed family).
  virtual std::optional<dealii::Tensor<2, dim>>
  particle_deformation_gradient(unsigned int i) const {
    (void)i;
    return std::nullopt;
  }
  virtual materials::MaterialState particle_state(unsigned int i) const {
    (void)i;
    return {};
  }
  // Per particle, the plastic work its committed history holds [J/m^3 of particle volume]: what
  // plastic flow dissipated, which an energy account adds to the stored energy (the FEM's
  // internal work holds both). Empty for methods without plastic history.
  virtual std::vector<double> plastic_work_density(const ParticleSet<dim>& particles) const {
    (void)particles;
    return {};
  }
  // Whether plastic_work_density has values (the same on every rank, whatever it holds).
  virtual bool has_plastic_work() const { return false; }
  // The method's own history for checkpoints (the particle set and bonds are saved by the
  // caller). A method without history writes nothing.
  virtual void save(std::ostream&) const {}
  virtual void load(std::istream&) {}
  // Messages for the run log since the last call (e.g. particles that lost their family).
  virtual std::vector<std::string> take_messages() { return {}; }
  // Per particle, the bonds of its row in short-range contact at the last force pass
  // (meshfree/short_range_forces.h), or null when the method has no such forces switched on.
  virtual const std::vector<unsigned int>* short_range_contacts() const { return nullptr; }
  // The short-range pairs' part of the stiffness bound at the current displacements (pairs in
  // contact or within 5 % of it; meshfree/short_range_forces.h), added into S in the units of
  // stiffness_bound(), which leaves it out. stable_time_step() includes it.
  virtual void add_contact_bound(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                 std::vector<double>& S) const {
    (void)particles;
    (void)bonds;
    (void)S;
  }
  // Whether the last force pass found a pair in short-range contact that the last contact
  // bound (add_contact_bound, stable_time_step) did not count: a relaxation renews its masses.
  virtual bool stiffness_bound_stale() const { return false; }
  // The short-range pairs born closer than their reference contact distance (converted
  // particles, meshfree/short_range_forces.h), for a checkpoint; restore_short_range_births()
  // after initialise() on a restart. Nothing without short-range forces.
  virtual std::vector<ShortRangeBirth> short_range_births() const { return {}; }
  virtual void restore_short_range_births(const std::vector<ShortRangeBirth>& births) {
    (void)births;
  }
  // Bytes of the method's own per-particle and per-bond arrays (capacities; heap memory inside
  // material states not counted). 0 for a method that does not count them.
  virtual std::size_t memory_bytes() const { return 0; }

  // Whether a bond that breaks changes forces beyond its two ends' rows, so every rank holding
  // a row of either end must learn of it (SPG: the pair leaves both RK shape-function rows,
  // which shape the forces on every particle of their support). A coupled run on several
  // ranks then gathers take_broken_pairs() after each force pass and hands the pairs to
  // break_pairs() everywhere.
  virtual bool shares_bond_breaks() const { return false; }
  // Pairs (i, j) broken by compute_forces since the last call.
  virtual std::vector<std::pair<unsigned int, unsigned int>> take_broken_pairs() { return {}; }
  // Where copies of a row live on several ranks (a distributed particle zone): compute_forces
  // decides only the pairs `decides` accepts, one rank per pair, and breaks nothing itself;
  // take_broken_pairs() returns those decisions, and the caller hands every rank's to
  // break_pairs() on every rank, so all copies of a row lose the same bonds at once.
  virtual void set_break_decider(std::function<bool(unsigned int, unsigned int)> decides) {
    (void)decides;
  }
  // Breaks these pairs (decided by another rank) in `bonds` and in the method's rows.
  virtual void break_pairs(ParticleSet<dim>& particles, BondList<dim>& bonds,
                           const std::vector<std::pair<unsigned int, unsigned int>>& pairs) {
    (void)particles;
    (void)bonds;
    (void)pairs;
  }
  // The energy-conserving splice of a coupled run (coupling/energy_splice.h) counts the
  // stored energy of everything the free particles' forces are computed from: every bond with
  // a free end (bond-based PD), every family with a row (NOSB-PD, SPG: the free particles and
  // the driven ones within a horizon of them). driven_reactions(): after compute_forces() at
  // the same state, the forces that energy puts on the driven particles of set_driven() [N]
  // (zero for the others; complete where every row within a horizon of the particle is here).
  // splice_energy_by_row(): that energy by the row (family centre) that holds it [J], so that
  // ranks holding copies of a row count it once. Nothing from a method that cannot provide
  // them (the splice then refuses it).
  virtual std::optional<std::vector<dealii::Tensor<1, dim>>>
  driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
    (void)particles;
    (void)bonds;
    return std::nullopt;
  }
  // A driven body the free particles are bonded to and whose FEM takes their forces back (an
  // implant meshed with the bone: coupling/implant_joint.h). After compute_forces() at the same
  // state: the forces the free particles exert on the driven particles flagged in `targets`,
  // as those receive them [N], summed over the rows whose centre has `counted` set (the rank
  // owning it), so that the targets' sum is the opposite of what the free particles receive
  // from them. Nothing from a method that cannot split its forces so (the joint refuses it).
  virtual std::optional<std::vector<dealii::Tensor<1, dim>>>
  joint_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                  const std::vector<std::uint8_t>& targets,
                  const std::vector<std::uint8_t>& counted) const {
    (void)particles;
    (void)bonds;
    (void)targets;
    (void)counted;
    return std::nullopt;
  }
  virtual std::optional<std::vector<double>>
  splice_energy_by_row(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const {
    (void)particles;
    (void)bonds;
    return std::nullopt;
  }

  // Physical displacements u_i [m] of the particles with rows here (what output shows): the
  // particle displacements themselves, except for methods whose unknowns are generalised
  // (SPG: RK coefficients d_J, u_I = Σ_J Ψ_J(X_I) d_J).
  virtual std::vector<dealii::Tensor<1, dim>>
  physical_displacements(const ParticleSet<dim>& particles) const {
    return particles.displacements();
  }
  // True when the particles' displacements are such generalised unknowns (output and errors
  // must then ask physical_displacements()).
  virtual bool generalised_displacements() const { return false; }
};

// A method whose parameters are read, waiting for its material: a coupled run learns E, ν and
// the law from the FEM cells it converts, after the scene was read.
template <int dim>
using ParticleMethodMaker =
    std::function<std::unique_ptr<ParticleMethod<dim>>(const ParticleMaterial& material)>;

// The registry entry of a method: its parameter subsection (declared inside whatever section
// holds particles, e.g. "Particles" or "Coupling") and, per dimension, a reader of that
// subsection returning the maker.
struct ParticleMethodEntry {
  std::string name;
  std::string description;
  std::string section; // parameter subsection of the method, e.g. "Bond based"
  std::function<void(dealii::ParameterHandler&)> declare;
  std::function<ParticleMethodMaker<2>(const dealii::ParameterHandler& section)> parse_2d;
  std::function<ParticleMethodMaker<3>(const dealii::ParameterHandler& section)> parse_3d;
};

using ParticleMethods = Registry<ParticleMethodEntry>;

// Declares every registered method's subsection in the current section of `prm`.
void declare_particle_method_sections(dealii::ParameterHandler& prm);

// "none|name|..." for Effects/Particles method, and the help text listing the methods.
std::string particle_method_choices();
std::string particle_method_documentation();

// Reads method `name`'s parameters from its subsection of the current section of `prm`
// (InvalidInput on a bad value, before any model is built). `where` names the parameter that
// chose the method, for the error on an unknown name.
template <int dim>
ParticleMethodMaker<dim> particle_method_maker(const std::string& name,
                                               dealii::ParameterHandler& prm,
                                               const std::string& where);

} // namespace spinesim::meshfree

// Registers a particle method at load time: the one line a new method adds besides its own
// files. `Class` is a template on dim with a `Parameters` type, static
// `declare(ParameterHandler&)` and `parse_parameters(const ParameterHandler&)`, and a
// constructor (const Parameters&, const ParticleMaterial&).
#define SPINESIM_REGISTER_PARTICLE_METHOD(Class, name, section, description)                       \
  namespace {                                                                                      \
  template <int dim>                                                                               \
  ::spinesim::meshfree::ParticleMethodMaker<dim>                                                   \
      spinesim_parse_particle_method_##Class(const dealii::ParameterHandler& s) {                  \
    auto p =                                                                                       \
        std::make_shared<const typename Class<dim>::Parameters>(Class<dim>::parse_parameters(s));  \
    return [p](const ::spinesim::meshfree::ParticleMaterial& m)                                    \
               -> std::unique_ptr<::spinesim::meshfree::ParticleMethod<dim>> {                     \
      return std::make_unique<Class<dim>>(*p, m);                                                  \
    };                                                                                             \
  }                                                                                                \
  const bool spinesim_particle_method_registered_##Class =                                         \
      ::spinesim::meshfree::ParticleMethods::instance().add(                                       \
          {name, description, section, &Class<2>::declare,                                         \
           &spinesim_parse_particle_method_##Class<2>,                                             \
           &spinesim_parse_particle_method_##Class<3>});                                           \
  }

#endif
