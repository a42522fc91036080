#ifndef SPINESIM_COUPLING_COUPLING_CHECKPOINT_H
#define SPINESIM_COUPLING_COUPLING_CHECKPOINT_H

// The particle side of a restart file (text, "spinesim_coupling 2"): clock, converted cells,
// every particle's record and state, broken bonds, the fracture-heat totals and the stick points
// of frictional contact with an implant. The FEM state
// is saved and restored separately.

#include "coupling/bond_rows.h"
#include "coupling/cell_converter.h"
#include "coupling/coupled_integrator.h"
#include "coupling/coupling_state.h"
#include "coupling/fracture_heat.h"
#include "coupling/ghost_layer.h"
#include "coupling/implant_joint.h"
#include "coupling/particle_halo.h"

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <string>

namespace spinesim::coupling {

template <int dim>
class CouplingCheckpoint {
 public:
  // The pieces whose state the file holds; `rebuild_layers` rebuilds the ghost layer, bonds
  // and interface after a load.
  struct Pieces {
    CouplingState<dim>& state;
    CellConverter<dim>& converter;
    CoupledIntegrator<dim>& integrator;
    FractureHeat<dim>& fracture;
    ParticleHalo<dim>& halo;
    BondRows<dim>& bond_rows;
    GhostLayer<dim>& ghosts;
    ImplantJoint<dim>& joint; // its contact's stick points
    std::function<void()> rebuild_layers;
  };
  explicit CouplingCheckpoint(Pieces pieces) : p_(std::move(pieces)) {}

  void save(const std::string& file) const; // collective; rank 0 writes
  void load(const std::string& file);       // every rank reads
  // The same file held in memory: the text on rank 0 (empty on the others; collective), and
  // its load from the same text on every rank (`name` names it in errors).
  std::string save_text() const;
  void load_text(const std::string& text, const std::string& name);

 private:
  // Collective; only rank 0 writes to `out`.
  void save_to(std::ostream& out) const;
  void load_from(std::istream& in, std::uintmax_t bytes, const std::string& name);

  Pieces p_;
};

} // namespace spinesim::coupling

#endif
