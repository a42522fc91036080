#ifndef SPINESIM_MESHFREE_PARTICLE_OUTPUT_H
#define SPINESIM_MESHFREE_PARTICLE_OUTPUT_H

// Particles as VTU point clouds for ParaView, through deal.II's DataOutBase (compressed
// binary VTU): current positions with displacement, velocity, damage, volume, material id
// and every named scalar field of the set.

#include "meshfree/particle_set.h"

#include <string>

namespace spinesim::meshfree {

// Writes `file_name` (.vtu). Call on one rank.
template <int dim>
void write_particles_vtu(const ParticleSet<dim>& particles, const std::string& file_name);

} // namespace spinesim::meshfree

#endif
