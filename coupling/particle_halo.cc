#include "coupling/particle_halo.h"

#include "meshfree/bond_loop.h"

#include <deal.II/base/exceptions.h>
#include <deal.II/base/mpi.h>

#include <set>
#include <string>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void ParticleHalo<dim>::plan(const MlsInterface<dim>& interface) {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  recv_.clear();
  send_.clear();
  if (Utilities::MPI::n_mpi_processes(comm) == 1) {
    state_.owner.clear(); // everything is owned
    return;
  }
  std::vector<int> owner(state_.particles.size(), -1);
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    if (state_.host_index[i] >= 0)
      owner[i] = static_cast<int>(state_.rank);
  state_.owner.resize(owner.size());
  MPI_Allreduce(owner.data(), state_.owner.data(), static_cast<int>(owner.size()), MPI_INT, MPI_MAX,
                comm);
  // Read here, owned elsewhere: bond partners of the owned rows and the MLS stencils of this
  // rank's interface nodes.
  std::set<unsigned int> needed;
  for (unsigned int i = 0; i < state_.bonds.n_particles(); ++i)
    meshfree::for_each_bond_of(state_.bonds, i, [&](std::size_t, unsigned int j) {
      if (!state_.is_owned(j))
        needed.insert(j);
    });
  for (const auto& entry : interface.dofs())
    for (const auto& [p, w] : entry.weights)
      if (!state_.is_owned(p))
        needed.insert(p);
  std::map<unsigned int, std::vector<unsigned int>> requests;
  for (const unsigned int j : needed) {
    AssertThrow(state_.owner[j] >= 0,
                ExcMessage("particle " + std::to_string(j) + " has no owner"));
    requests[static_cast<unsigned int>(state_.owner[j])].push_back(j);
  }
  recv_ = requests;
  send_ = Utilities::MPI::some_to_some(comm, requests);
}

template <int dim>
void ParticleHalo<dim>::exchange() {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr int tag = 7301;
  // u, v, and with ghost gradients from the FEM the gradient F (dim × dim) of every particle
  // (a free particle's entry is the identity, never read)
  const bool with_gradient = state_.ghost_gradients_from_fem();
  const unsigned int width = 2 * dim + (with_gradient ? dim * dim : 0);
  std::vector<std::vector<double>> out, in;
  std::vector<MPI_Request> requests;
  for (const auto& [rank, list] : send_) {
    out.emplace_back();
    auto& b = out.back();
    b.reserve(width * list.size());
    for (const unsigned int i : list)
      for (unsigned int d = 0; d < dim; ++d)
        b.push_back(state_.particles.displacement(i)[d]);
    for (const unsigned int i : list)
      for (unsigned int d = 0; d < dim; ++d)
        b.push_back(state_.particles.velocity(i)[d]);
    for (const unsigned int i : list)
      for (unsigned int c = 0; with_gradient && c < dim * dim; ++c)
        b.push_back(state_.driven_gradients[i][c / dim][c % dim]);
  }
  requests.reserve(send_.size() + recv_.size());
  for (const auto& [rank, list] : recv_) {
    in.emplace_back(width * list.size());
    requests.emplace_back();
    MPI_Irecv(in.back().data(), static_cast<int>(in.back().size()), MPI_DOUBLE,
              static_cast<int>(rank), tag, comm, &requests.back());
  }
  std::size_t k = 0;
  for (const auto& [rank, list] : send_) {
    requests.emplace_back();
    MPI_Isend(out[k].data(), static_cast<int>(out[k].size()), MPI_DOUBLE, static_cast<int>(rank),
              tag, comm, &requests.back());
    ++k;
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  k = 0;
  for (const auto& [rank, list] : recv_) {
    const auto& b = in[k++];
    const std::size_t n = list.size();
    for (std::size_t m = 0; m < n; ++m) {
      for (unsigned int d = 0; d < dim; ++d) {
        state_.particles.displacement(list[m])[d] = b[dim * m + d];
        state_.particles.velocity(list[m])[d] = b[dim * n + dim * m + d];
      }
      for (unsigned int c = 0; with_gradient && c < dim * dim; ++c)
        state_.driven_gradients[list[m]][c / dim][c % dim] = b[2 * dim * n + dim * dim * m + c];
    }
  }
}

template <int dim>
void ParticleHalo<dim>::exchange_temperatures() {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr int tag = 7303;
  std::vector<std::vector<double>> out, in;
  std::vector<MPI_Request> requests;
  requests.reserve(send_.size() + recv_.size());
  out.reserve(send_.size());
  in.reserve(recv_.size());
  for (const auto& [rank, list] : recv_) {
    in.emplace_back(list.size());
    requests.emplace_back();
    MPI_Irecv(in.back().data(), static_cast<int>(list.size()), MPI_DOUBLE, static_cast<int>(rank),
              tag, comm, &requests.back());
  }
  for (const auto& [rank, list] : send_) {
    out.emplace_back();
    for (const unsigned int i : list)
      out.back().push_back(state_.particles.temperature(i));
    requests.emplace_back();
    MPI_Isend(out.back().data(), static_cast<int>(list.size()), MPI_DOUBLE, static_cast<int>(rank),
              tag, comm, &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  std::size_t k = 0;
  for (const auto& [rank, list] : recv_) {
    const auto& b = in[k++];
    for (std::size_t m = 0; m < list.size(); ++m)
      state_.particles.temperature(list[m]) = b[m];
  }
}

template <int dim>
void ParticleHalo<dim>::add_to_owners(std::vector<Tensor<1, dim>>& values) const {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr int tag = 7302;
  std::vector<std::vector<double>> out, in;
  std::vector<MPI_Request> requests;
  requests.reserve(send_.size() + recv_.size());
  in.reserve(send_.size());
  out.reserve(recv_.size());
  for (const auto& [rank, list] : send_) {
    in.emplace_back(dim * list.size());
    requests.emplace_back();
    MPI_Irecv(in.back().data(), static_cast<int>(in.back().size()), MPI_DOUBLE,
              static_cast<int>(rank), tag, comm, &requests.back());
  }
  for (const auto& [rank, list] : recv_) {
    out.emplace_back();
    auto& b = out.back();
    b.reserve(dim * list.size());
    for (const unsigned int i : list) {
      for (unsigned int d = 0; d < dim; ++d)
        b.push_back(values[i][d]);
      values[i] = Tensor<1, dim>();
    }
    requests.emplace_back();
    MPI_Isend(b.data(), static_cast<int>(b.size()), MPI_DOUBLE, static_cast<int>(rank), tag, comm,
              &requests.back());
  }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);
  std::size_t k = 0;
  for (const auto& [rank, list] : send_) {
    const auto& b = in[k++];
    for (std::size_t m = 0; m < list.size(); ++m)
      for (unsigned int d = 0; d < dim; ++d)
        values[list[m]][d] += b[dim * m + d];
  }
}

template <int dim>
void ParticleHalo<dim>::synchronise() const {
  auto& p = state_.particles; // the replicated set: a cache that every rank refreshes
  if (state_.method && state_.n_free_particles() > 0)
    state_.method->update_damage(p, state_.bonds); // owned rows
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) == 1)
    return;
  constexpr unsigned int width = 2 * dim + 2; // u, v, damage, temperature
  std::vector<double> buffer(width * state_.particles.size(), 0.0);
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    if (state_.is_owned(i)) {
      double* b = &buffer[width * i];
      for (unsigned int d = 0; d < dim; ++d) {
        b[d] = state_.particles.displacement(i)[d];
        b[dim + d] = state_.particles.velocity(i)[d];
      }
      b[2 * dim] = state_.particles.damage(i);
      b[2 * dim + 1] = state_.particles.temperature(i);
    }
  Utilities::MPI::sum(buffer, comm, buffer);
  for (unsigned int i = 0; i < state_.particles.size(); ++i) {
    const double* b = &buffer[width * i];
    for (unsigned int d = 0; d < dim; ++d) {
      p.displacement(i)[d] = b[d];
      p.velocity(i)[d] = b[dim + d];
    }
    p.damage(i) = b[2 * dim];
    p.temperature(i) = b[2 * dim + 1];
  }
}

template class ParticleHalo<2>;
template class ParticleHalo<3>;

} // namespace spinesim::coupling
