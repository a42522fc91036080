#ifndef SPINESIM_COUPLING_PARTICLE_RECORD_H
#define SPINESIM_COUPLING_PARTICLE_RECORD_H

// A particle as made from a cell (by a conversion or for the ghost layer) on the rank that
// owns the cell, and as exchanged between ranks (boost serialization through deal.II's
// Utilities::MPI::all_gather): everything the other ranks need to add it.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/law_parameters.h"

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <cstdint>
#include <string>

namespace spinesim::coupling {

template <int dim>
struct ParticleRecord {
  std::string cell;              // CellId of the host cell (text form)
  unsigned int point = 0;        // index of the point within the cell
  bool free = false;             // a converted cell's particle (else a ghost)
  std::uint32_t fixed_slots = 0; // Dirichlet slots whose boundary the host cell touches
  double volume = 0;             // [m^3]
  double density = 0;            // [kg/m^3]
  double temperature = 0;        // [K]
  dealii::Point<dim> position;   // reference position [m]
  dealii::Tensor<1, dim> displacement, velocity; // [m], [m/s]
  // Of the fixed components: displacement at conversion less the prescribed value there [m]
  // (ParticleBoundary holds u = g(X, t) + offset).
  dealii::Tensor<1, dim> support_offset;
  // The host cell's constitutive law, which the particle runs on (CouplingState::laws).
  materials::LawParameters law;
  // The cell's constitutive state at the particle (nearest quadrature point); only for
  // methods that carry material state.
  bool has_state = false;
  materials::MaterialState state;
  // The point's deformation gradient now (finite strain: F̄ of an F-bar cell at the current
  // displacement; the particles continue the state at their own F, meshfree::CarriedState).
  bool has_state_deformation = false;
  materials::Tensor2 state_deformation;

  template <class Archive>
  void serialize(Archive& ar, const unsigned int) {
    ar& cell& point& free& fixed_slots& volume& density& temperature& position& displacement&
        velocity& support_offset& law& has_state;
    if (has_state)
      ar& state.plastic_strain& state.elastic_left_cauchy_green& state
          .equivalent_plastic_strain& state.plastic_work& state
          .fracture_damage& has_state_deformation;
    if (has_state && has_state_deformation)
      ar& state_deformation;
  }

  bool operator==(const ParticleRecord& o) const {
    return cell == o.cell && point == o.point && free == o.free && fixed_slots == o.fixed_slots &&
           volume == o.volume && density == o.density && temperature == o.temperature &&
           position == o.position && displacement == o.displacement && velocity == o.velocity &&
           support_offset == o.support_offset && law.same_law(o.law);
  }
};

} // namespace spinesim::coupling

#endif
