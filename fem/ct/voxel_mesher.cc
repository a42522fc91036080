#include "fem/ct/voxel_mesher.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <queue>
#include <sstream>

namespace spinesim::fem {

void VoxelMesher::repair_non_manifold(std::vector<char>& kept,
                                      const std::vector<unsigned int>& score,
                                      const std::array<unsigned int, 3>& nb) {
  auto index = [&](const std::array<long, 3>& B) {
    return B[0] + std::size_t(nb[0]) * (B[1] + std::size_t(nb[1]) * B[2]);
  };
  // Adds the empty candidate with the most selected voxels (ties: the first).
  auto fill_best = [&](const std::vector<std::size_t>& candidates) {
    std::size_t best = candidates.front();
    for (std::size_t c : candidates)
      if (score[c] > score[best])
        best = c;
    kept[best] = 1;
  };
  bool changed = true;
  while (changed) {
    changed = false;
    // Edges: four blocks around an edge along axis a, kept on one diagonal only.
    for (unsigned int a = 0; a < 3; ++a) {
      const unsigned int b = (a + 1) % 3, c = (a + 2) % 3;
      std::array<long, 3> X;
      for (X[a] = 0; X[a] < long(nb[a]); ++X[a])
        for (X[b] = 0; X[b] + 1 < long(nb[b]); ++X[b])
          for (X[c] = 0; X[c] + 1 < long(nb[c]); ++X[c]) {
            auto Y = X, Z = X, W = X;
            Y[b] += 1;
            Z[c] += 1;
            W[b] += 1;
            W[c] += 1;
            const std::size_t x = index(X), y = index(Y), z = index(Z), w = index(W);
            if (kept[x] && kept[w] && !kept[y] && !kept[z]) {
              fill_best({y, z});
              changed = true;
            } else if (kept[y] && kept[z] && !kept[x] && !kept[w]) {
              fill_best({x, w});
              changed = true;
            }
          }
    }
    if (changed)
      continue; // vertex patterns are only checked on an edge-manifold set
    // Vertices: with every edge manifold, the only non-manifold 2x2x2 pattern is two opposite
    // corners with the other six empty; fill one of the six and let the edge pass finish.
    std::array<long, 3> X;
    for (X[2] = 0; X[2] + 1 < long(nb[2]); ++X[2])
      for (X[1] = 0; X[1] + 1 < long(nb[1]); ++X[1])
        for (X[0] = 0; X[0] + 1 < long(nb[0]); ++X[0]) {
          std::array<std::size_t, 8> s;
          unsigned int n_kept = 0;
          for (unsigned int v = 0; v < 8; ++v) {
            auto Y = X;
            Y[0] += v & 1;
            Y[1] += (v >> 1) & 1;
            Y[2] += (v >> 2) & 1;
            s[v] = index(Y);
            n_kept += kept[s[v]] != 0;
          }
          if (n_kept != 2)
            continue;
          for (unsigned int v = 0; v < 4; ++v)
            if (kept[s[v]] && kept[s[7 - v]]) {
              std::vector<std::size_t> others;
              for (unsigned int u = 0; u < 8; ++u)
                if (u != v && u != 7 - v)
                  others.push_back(s[u]);
              fill_best(others);
              changed = true;
            }
        }
  }
}

double VoxelMesh::total_volume() const {
  return std::accumulate(cell_volume.begin(), cell_volume.end(), 0.0);
}

double VoxelMesh::total_mass() const {
  double m = 0;
  for (std::size_t c = 0; c < cell_volume.size(); ++c)
    m += 1000.0 * cell_density[c] * cell_volume[c]; // g/cm^3 -> kg/m^3
  return m;
}

VoxelMesher::VoxelMesher(const VolumeGeometry& grid, std::vector<double> density,
                         const LabelVolume* labels, Options options)
    : grid_(grid), density_(std::move(density)), options_(std::move(options)) {
  if (density_.size() != grid_.n_voxels())
    throw InvalidInput("VoxelMesher", "density array does not match the image grid",
                       "one density per voxel");
  if (options_.coarsening_factor < 1)
    throw InvalidInput("Coarsening factor", "0", "an integer >= 1");
  for (int l : options_.labels)
    if (l < 0 || l > 254)
      throw InvalidInput("Labels", "label " + std::to_string(l) + " cannot be a material id",
                         "labels in [0, 254]");
  if (!options_.labels.empty()) {
    if (labels == nullptr)
      throw InvalidInput("Label file", "labels are selected but no label volume is given",
                         "a label image on the same grid, or an empty Labels list");
    if (!labels->same_grid(grid_))
      throw InvalidInput(labels->file_name,
                         "label volume grid (size, spacing, origin, direction) differs from "
                         "the image",
                         "a segmentation on the image's voxel grid");
    labels_ = labels->labels;
  }
}

VoxelMesh VoxelMesher::build(dealii::Triangulation<3>& triangulation) const {
  const unsigned int f = options_.coarsening_factor;
  const bool label_mode = !options_.labels.empty();
  const auto& n = grid_.size;
  std::array<unsigned int, 3> nb; // blocks per axis
  for (unsigned int d = 0; d < 3; ++d)
    nb[d] = (n[d] + f - 1) / f;
  const std::size_t n_blocks = std::size_t(nb[0]) * nb[1] * nb[2];
  auto block_index = [&](unsigned int I, unsigned int J, unsigned int K) {
    return I + std::size_t(nb[0]) * (J + std::size_t(nb[1]) * K);
  };

  VoxelMesh mesh;
  const double voxel_volume = grid_.voxel_volume();

  // Per block: selected voxels, their density sum and their most frequent label.
  std::vector<unsigned int> n_sel(n_blocks, 0), n_tot(n_blocks, 0);
  std::vector<double> rho_sum(n_blocks, 0.0);
  std::vector<int> block_label(n_blocks, 0);
  std::vector<int> selected_label(options_.labels);
  std::sort(selected_label.begin(), selected_label.end());
  std::vector<unsigned int> histogram(selected_label.size());
  auto is_selected = [&](std::size_t v, int& which) {
    if (!label_mode)
      return density_[v] >= options_.density_threshold;
    const auto it = std::lower_bound(selected_label.begin(), selected_label.end(), labels_[v]);
    which = int(it - selected_label.begin());
    return it != selected_label.end() && *it == labels_[v];
  };

  for (unsigned int K = 0; K < nb[2]; ++K)
    for (unsigned int J = 0; J < nb[1]; ++J)
      for (unsigned int I = 0; I < nb[0]; ++I) {
        const std::size_t b = block_index(I, J, K);
        std::fill(histogram.begin(), histogram.end(), 0u);
        for (unsigned int k = K * f; k < std::min((K + 1) * f, n[2]); ++k)
          for (unsigned int j = J * f; j < std::min((J + 1) * f, n[1]); ++j)
            for (unsigned int i = I * f; i < std::min((I + 1) * f, n[0]); ++i) {
              const std::size_t v = grid_.linear_index(i, j, k);
              ++n_tot[b];
              int which = -1;
              if (!is_selected(v, which))
                continue;
              ++n_sel[b];
              rho_sum[b] += density_[v];
              if (label_mode)
                ++histogram[which];
            }
        if (label_mode && n_sel[b] > 0)
          block_label[b] = selected_label[std::max_element(histogram.begin(), histogram.end()) -
                                          histogram.begin()];
        mesh.n_selected_voxels += n_sel[b];
        mesh.selected_mass += 1000.0 * rho_sum[b] * voxel_volume;
      }
  mesh.selected_volume = mesh.n_selected_voxels * voxel_volume;
  if (mesh.n_selected_voxels == 0) {
    std::ostringstream what;
    if (label_mode)
      what << "no voxel carries one of the selected labels";
    else
      what << "no voxel reaches the density threshold " << options_.density_threshold << " g/cm^3";
    throw InvalidInput("Labels / Density threshold", what.str(),
                       "a selection that contains at least one voxel");
  }

  // Block rule. Majority ties (exactly half, frequent for even factors) are decided by the
  // selected fraction in the block grown by one voxel on every side: keeping all ties biases
  // the volume outwards (+7.6 % mass on verse004 at f = 2), dropping them inwards (-6.8 %).
  auto selected_in_window = [&](unsigned int I, unsigned int J, unsigned int K) {
    const std::array<unsigned int, 3> B{{I, J, K}};
    std::array<long, 3> lo, hi;
    for (unsigned int d = 0; d < 3; ++d) {
      lo[d] = std::max(0L, long(B[d] * f) - 1);
      hi[d] = std::min(long(n[d]), long((B[d] + 1) * f) + 1);
    }
    std::size_t in = 0, all = 0;
    for (long k = lo[2]; k < hi[2]; ++k)
      for (long j = lo[1]; j < hi[1]; ++j)
        for (long i = lo[0]; i < hi[0]; ++i) {
          int which = -1;
          ++all;
          in += is_selected(grid_.linear_index(i, j, k), which);
        }
    return 2 * in >= all;
  };
  std::vector<char> kept(n_blocks, 0);
  for (unsigned int K = 0; K < nb[2]; ++K)
    for (unsigned int J = 0; J < nb[1]; ++J)
      for (unsigned int I = 0; I < nb[0]; ++I) {
        const std::size_t b = block_index(I, J, K);
        if (n_sel[b] == 0)
          continue;
        if (options_.block_rule == BlockRule::any || 2 * n_sel[b] > n_tot[b])
          kept[b] = 1;
        else if (2 * n_sel[b] == n_tot[b])
          kept[b] = selected_in_window(I, J, K);
      }

  std::vector<unsigned int> n_mean = n_sel; // voxels averaged into the cell density
  if (options_.repair_non_manifold) {
    const std::vector<char> before = kept;
    repair_non_manifold(kept, n_sel, nb);
    // Filled blocks take the mean density of their own voxels (the tissue the image shows
    // there) and the most frequent label of their kept face neighbours.
    for (unsigned int K = 0; K < nb[2]; ++K)
      for (unsigned int J = 0; J < nb[1]; ++J)
        for (unsigned int I = 0; I < nb[0]; ++I) {
          const std::size_t b = block_index(I, J, K);
          if (!kept[b] || before[b])
            continue;
          ++mesh.n_added_cells;
          if (n_sel[b] > 0)
            continue; // density and label of its own selected voxels
          double sum = 0;
          for (unsigned int k = K * f; k < std::min((K + 1) * f, n[2]); ++k)
            for (unsigned int j = J * f; j < std::min((J + 1) * f, n[1]); ++j)
              for (unsigned int i = I * f; i < std::min((I + 1) * f, n[0]); ++i)
                sum += density_[grid_.linear_index(i, j, k)];
          rho_sum[b] = sum;
          n_mean[b] = n_tot[b];
          std::map<int, unsigned int> votes;
          const int step[6][3] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                  {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
          for (const auto& st : step) {
            const long I2 = long(I) + st[0], J2 = long(J) + st[1], K2 = long(K) + st[2];
            if (I2 < 0 || J2 < 0 || K2 < 0 || I2 >= nb[0] || J2 >= nb[1] || K2 >= nb[2])
              continue;
            const std::size_t b2 = block_index(I2, J2, K2);
            if (before[b2])
              ++votes[block_label[b2]];
          }
          int best = block_label[b];
          unsigned int most = 0;
          for (const auto& [label, count] : votes)
            if (count > most) {
              most = count;
              best = label;
            }
          block_label[b] = best;
        }
  }

  // Face-connected components (breadth first), then keep the largest.
  std::vector<int> component(n_blocks, -1);
  std::vector<std::size_t> component_size;
  for (std::size_t seed = 0; seed < n_blocks; ++seed) {
    if (!kept[seed] || component[seed] >= 0)
      continue;
    const int c = int(component_size.size());
    component_size.push_back(0);
    std::queue<std::size_t> front;
    front.push(seed);
    component[seed] = c;
    while (!front.empty()) {
      const std::size_t b = front.front();
      front.pop();
      ++component_size[c];
      const unsigned int I = b % nb[0], J = (b / nb[0]) % nb[1],
                         K = b / (std::size_t(nb[0]) * nb[1]);
      const int step[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
      for (const auto& s : step) {
        const long I2 = long(I) + s[0], J2 = long(J) + s[1], K2 = long(K) + s[2];
        if (I2 < 0 || J2 < 0 || K2 < 0 || I2 >= nb[0] || J2 >= nb[1] || K2 >= nb[2])
          continue;
        const std::size_t b2 = block_index(I2, J2, K2);
        if (kept[b2] && component[b2] < 0) {
          component[b2] = c;
          front.push(b2);
        }
      }
    }
  }
  mesh.n_components = static_cast<unsigned int>(component_size.size());
  if (options_.keep_largest_component && component_size.size() > 1) {
    const int largest = int(std::max_element(component_size.begin(), component_size.end()) -
                            component_size.begin());
    for (std::size_t b = 0; b < n_blocks; ++b)
      if (kept[b] && component[b] != largest) {
        kept[b] = 0;
        ++mesh.n_dropped_cells;
        mesh.n_dropped_voxels += n_sel[b];
      }
  }

  // Vertices at block corners, numbered on first use; cells in block order.
  const std::array<unsigned int, 3> nc{{nb[0] + 1, nb[1] + 1, nb[2] + 1}};
  const std::size_t n_corners = std::size_t(nc[0]) * nc[1] * nc[2];
  std::vector<int> vertex_of_corner(n_corners, -1);
  std::vector<dealii::Point<3>> vertices;
  std::vector<dealii::CellData<3>> cells;
  const bool mirror = grid_.handedness() < 0;
  auto corner_coordinate = [&](unsigned int B, unsigned int d) {
    return double(std::min(B * f, n[d])) - 0.5; // voxel-index coordinate of a block boundary
  };
  for (unsigned int K = 0; K < nb[2]; ++K)
    for (unsigned int J = 0; J < nb[1]; ++J)
      for (unsigned int I = 0; I < nb[0]; ++I) {
        const std::size_t b = block_index(I, J, K);
        if (!kept[b])
          continue;
        dealii::CellData<3> cell;
        for (unsigned int v = 0; v < 8; ++v) {
          const unsigned int a = (v & 1) ? 1 : 0, bb = (v & 2) ? 1 : 0, c = (v & 4) ? 1 : 0;
          const unsigned int ci = I + (mirror ? 1 - a : a), cj = J + bb, ck = K + c;
          const std::size_t key = ci + std::size_t(nc[0]) * (cj + std::size_t(nc[1]) * ck);
          if (vertex_of_corner[key] < 0) {
            vertex_of_corner[key] = int(vertices.size());
            vertices.push_back(grid_.point(corner_coordinate(ci, 0), corner_coordinate(cj, 1),
                                           corner_coordinate(ck, 2)));
          }
          cell.vertices[v] = static_cast<unsigned int>(vertex_of_corner[key]);
        }
        cell.material_id = label_mode ? dealii::types::material_id(block_label[b]) : 0;
        cells.push_back(cell);
        const std::array<unsigned int, 3> B{{I, J, K}};
        unsigned int clipped = 1; // voxels in the block, fewer at the image edge
        for (unsigned int d = 0; d < 3; ++d)
          clipped *= std::min((B[d] + 1) * f, n[d]) - B[d] * f;
        mesh.cell_density.push_back(rho_sum[b] / n_mean[b]);
        mesh.cell_volume.push_back(clipped * voxel_volume);
        mesh.cell_first_voxel.push_back({{I * f, J * f, K * f}});
      }

  triangulation.create_triangulation(vertices, cells, dealii::SubCellData());

  // parallel::distributed::Triangulation renumbers coarse cells (and vertices), so the per-cell
  // data is re-indexed by coarse cell id, finding each cell's block from its centre.
  std::vector<int> creation_of_block(n_blocks, -1);
  for (std::size_t c = 0; c < mesh.cell_first_voxel.size(); ++c) {
    const auto& v = mesh.cell_first_voxel[c];
    creation_of_block[block_index(v[0] / f, v[1] / f, v[2] / f)] = int(c);
  }
  VoxelMesh by_id = mesh;
  for (const auto& cell : triangulation.cell_iterators_on_level(0)) {
    const dealii::Point<3> x = cell->center();
    std::array<long, 3> B;
    for (unsigned int c = 0; c < 3; ++c) {
      double t = 0; // voxel-index coordinate: D^T (x - origin) / spacing
      for (unsigned int r = 0; r < 3; ++r)
        t += grid_.direction[r][c] * (x[r] - grid_.origin[r]);
      B[c] = long(std::floor((t / grid_.spacing[c] + 0.5) / f));
    }
    const auto id = cell->id().get_coarse_cell_id();
    const bool inside =
        B[0] >= 0 && B[1] >= 0 && B[2] >= 0 && B[0] < nb[0] && B[1] < nb[1] && B[2] < nb[2];
    const int c = inside ? creation_of_block[block_index(B[0], B[1], B[2])] : -1;
    if (c < 0 || id >= cells.size()) {
      std::ostringstream where;
      where << "voxel mesher, coarse cell " << id << " at " << x;
      throw NumericalFailure("cannot match a coarse cell to its voxel block", where.str(),
                             "the image direction matrix may not be orthonormal");
    }
    by_id.cell_density[id] = mesh.cell_density[c];
    by_id.cell_volume[id] = mesh.cell_volume[c];
    by_id.cell_first_voxel[id] = mesh.cell_first_voxel[c];
    for (const unsigned int face : cell->face_indices())
      if (cell->face(face)->at_boundary()) {
        const auto it = options_.label_boundary_ids.find(cell->material_id());
        cell->face(face)->set_boundary_id(it == options_.label_boundary_ids.end() ? 0 : it->second);
      }
  }
  return by_id;
}

} // namespace spinesim::fem
