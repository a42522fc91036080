#include "fem/explicit_energy.h"

#include <deal.II/base/array_view.h>
#include <deal.II/base/mpi.h>

namespace spinesim::fem {

EnergyBalance sum_energy(const std::vector<const ExplicitEnergy*>& parts, double fracture,
                         MPI_Comm comm) {
  double v[9] = {0, 0, 0, 0, 0, 0, fracture, 0, 1};
  for (const auto* p : parts) {
    v[0] = std::max(v[0], p->time);
    v[1] += p->external.at_force_pass;
    v[2] += p->interface.at_force_pass;
    v[3] += p->stored_or_internal();
    v[4] += p->kinetic;
    v[5] += p->kinetic_central;
    v[7] += p->damping.at_force_pass;
    v[8] = std::min(v[8], p->valid ? 1.0 : 0.0);
  }
  double time = dealii::Utilities::MPI::max(v[0], comm);
  double valid = dealii::Utilities::MPI::min(v[8], comm);
  dealii::Utilities::MPI::sum(dealii::ArrayView<const double>(v, 8), comm,
                              dealii::ArrayView<double>(v, 8));
  EnergyBalance b;
  b.time = time;
  b.external_work = v[1];
  b.interface_work = v[2];
  b.strain_energy = v[3];
  b.kinetic_energy = v[4];
  b.kinetic_energy_central = v[5];
  b.fracture_dissipation = v[6];
  b.damping_dissipation = v[7];
  b.valid = valid > 0;
  return b;
}

} // namespace spinesim::fem
