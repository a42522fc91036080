#ifndef SPINESIM_MESHFREE_SPG_SPG_VTU_WRITER_H
#define SPINESIM_MESHFREE_SPG_SPG_VTU_WRITER_H

// ParaView output of an SPG run: <base>_<cycle>.vtu point clouds (through
// meshfree/particle_output) and the <base>.pvd time series, each written to a ".tmp" file and
// renamed, so a reader never sees a half-written file.
//
// ParticleSet::displacement holds RK coefficients, not displacements, so the written set is a
// copy at the physical state: position X + u_h, displacement u_h = Σ Ψ_J d_J, velocity
// Σ Ψ_J v_J, damage, volume, and the scalar fields equivalent_plastic_strain, the Cauchy
// stress stress_xx, _yy, _zz, _xy, _yz, _xz and von_mises_stress [Pa] (SPGSolver::cauchy_stress;
// in 2-D the plane-strain σ_zz is included).

#include "meshfree/particle_set.h"
#include "meshfree/spg/spg_solver.h"

#include <string>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class SPGVtuWriter {
 public:
  // `directory` must exist; files are <directory>/<base>_<cycle, 4 digits>.vtu and <base>.pvd.
  explicit SPGVtuWriter(std::string directory, std::string base = "particles");

  // The physical particle set of the solver's last force evaluation.
  static ParticleSet<dim> physical_particles(const SPGSolver<dim>& solver,
                                             const ParticleSet<dim>& particles);

  // Writes the next cycle at `time` [s] and rewrites the .pvd. Returns the .vtu file name
  // (without the directory). Call on one rank. InvalidInput if the directory is not writable.
  std::string write(const SPGSolver<dim>& solver, const ParticleSet<dim>& particles, double time);

  const std::vector<std::pair<double, std::string>>& records() const { return records_; }

  // Re-reads every written .vtu: true if each exists, has the VTK XML header, the expected
  // point count and the closing tag, and the .pvd lists them all (a cheap parse check).
  bool verify(unsigned int n_points) const;

 private:
  std::string directory_, base_;
  std::vector<std::pair<double, std::string>> records_;
};

} // namespace spinesim::meshfree

#endif
