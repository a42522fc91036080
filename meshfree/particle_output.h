#ifndef SPINESIM_MESHFREE_PARTICLE_OUTPUT_H
#define SPINESIM_MESHFREE_PARTICLE_OUTPUT_H

// Particles as VTU point clouds for ParaView, through deal.II's DataOutBase (compressed
// binary VTU): current positions with displacement, velocity, damage, volume, material id
// and every named scalar field of the set.

#include "meshfree/particle_set.h"

#include <string>
#include <vector>

namespace spinesim::meshfree {

// Writes `file_name` (.vtu): the first `count` particles (all by default; a distributed zone
// writes its owned particles, which come first).
template <int dim>
void write_particles_vtu(const ParticleSet<dim>& particles, const std::string& file_name,
                         unsigned int count = ~0u);

// Writes the .pvtu record joining the per-rank pieces (file names relative to it) written by
// write_particles_vtu for particle sets with the fields of `particles`. Call on one rank.
template <int dim>
void write_particles_pvtu(const ParticleSet<dim>& particles, const std::string& file_name,
                          const std::vector<std::string>& pieces);

} // namespace spinesim::meshfree

#endif
