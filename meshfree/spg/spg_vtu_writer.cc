#include "meshfree/spg/spg_vtu_writer.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"
#include "meshfree/particle_output.h"

#include <deal.II/base/data_out_base.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace spinesim::meshfree {

namespace {
// Renames tmp → final; InvalidInput naming the file on failure.
void commit(const std::string& tmp, const std::string& final_name) {
  std::error_code ec;
  std::filesystem::rename(tmp, final_name, ec);
  if (ec)
    throw InvalidInput("SPG output", "cannot rename " + tmp + ": " + ec.message(),
                       "a writable run directory");
}
} // namespace

template <int dim>
SPGVtuWriter<dim>::SPGVtuWriter(std::string directory, std::string base)
    : directory_(std::move(directory)), base_(std::move(base)) {}

template <int dim>
ParticleSet<dim> SPGVtuWriter<dim>::physical_particles(const SPGSolver<dim>& s,
                                                       const ParticleSet<dim>& p) {
  ParticleSet<dim> out(p.thickness());
  const unsigned int n = p.size();
  const auto& rk = s.shape_functions();
  const auto& bonds = s.bonds();
  const auto& uh = s.physical_displacements();
  static const char* names[3][3] = {{"stress_xx", "stress_xy", "stress_xz"},
                                    {"stress_xy", "stress_yy", "stress_yz"},
                                    {"stress_xz", "stress_yz", "stress_zz"}};
  for (unsigned int i = 0; i < n; ++i) {
    out.add_particle(p.reference_position(i), p.volume(i));
    out.material_id(i) = p.material_id(i);
  }
  auto& eps = out.add_scalar_field("equivalent_plastic_strain");
  std::vector<std::vector<double>*> stress(dim * dim, nullptr);
  for (unsigned int a = 0; a < dim; ++a)
    for (unsigned int b = a; b < dim; ++b)
      stress[a * dim + b] = &out.add_scalar_field(names[a][b]);
  std::vector<double>* mises = dim == 3 ? &out.add_scalar_field("von_mises_stress") : nullptr;
  for (unsigned int i = 0; i < n; ++i) {
    out.displacement(i) = uh[i];
    // The velocity is the time derivative of u_h = Σ Ψ_J(X^r_I) d_J (+ a constant shift).
    dealii::Tensor<1, dim> v = rk.self_value[i] * p.velocity(i);
    for_each_bond_of(bonds, i,
                     [&](std::size_t k, unsigned int j) { v += rk.value[k] * p.velocity(j); });
    out.velocity(i) = v;
    out.damage(i) = p.damage(i);
    eps[i] = s.states()[i].equivalent_plastic_strain;
    const auto& F = s.deformation_gradients()[i];
    const double J = dealii::determinant(F);
    const dealii::Tensor<2, dim> sigma =
        J > 0 ? (1.0 / J) * s.first_piola_stresses()[i] * transpose(F) : dealii::Tensor<2, dim>();
    for (unsigned int a = 0; a < dim; ++a)
      for (unsigned int b = a; b < dim; ++b)
        (*stress[a * dim + b])[i] = sigma[a][b];
    if (mises) {
      const double tr = dealii::trace(sigma) / 3.0;
      dealii::Tensor<2, dim> dev = sigma;
      for (unsigned int a = 0; a < dim; ++a)
        dev[a][a] -= tr;
      (*mises)[i] = std::sqrt(1.5 * dealii::scalar_product(dev, dev));
    }
  }
  return out;
}

template <int dim>
std::string SPGVtuWriter<dim>::write(const SPGSolver<dim>& solver, const ParticleSet<dim>& p,
                                     double time) {
  std::ostringstream name;
  name << base_ << "_" << std::setw(4) << std::setfill('0') << records_.size() << ".vtu";
  const std::string path = directory_ + "/" + name.str();
  write_particles_vtu(physical_particles(solver, p), path + ".tmp");
  if (!std::ifstream(path + ".tmp"))
    throw InvalidInput("SPG output", "cannot write " + path, "a writable run directory");
  commit(path + ".tmp", path);
  records_.emplace_back(time, name.str());
  const std::string pvd = directory_ + "/" + base_ + ".pvd";
  {
    std::ofstream out(pvd + ".tmp");
    dealii::DataOutBase::write_pvd_record(out, records_);
    if (!out)
      throw InvalidInput("SPG output", "cannot write " + pvd, "a writable run directory");
  }
  commit(pvd + ".tmp", pvd);
  return name.str();
}

template <int dim>
bool SPGVtuWriter<dim>::verify(unsigned int n_points) const {
  const auto slurp = [](const std::string& f, std::string& text) {
    std::ifstream in(f);
    if (!in)
      return false;
    std::ostringstream s;
    s << in.rdbuf();
    text = s.str();
    return true;
  };
  std::string pvd;
  if (records_.empty() || !slurp(directory_ + "/" + base_ + ".pvd", pvd) ||
      pvd.find("</VTKFile>") == std::string::npos)
    return false;
  const std::string points = "NumberOfPoints=\"" + std::to_string(n_points) + "\"";
  for (const auto& r : records_) {
    std::string vtu;
    if (!slurp(directory_ + "/" + r.second, vtu) || vtu.rfind("<?xml", 0) != 0 ||
        vtu.find("<VTKFile type=\"UnstructuredGrid\"") == std::string::npos ||
        vtu.find(points) == std::string::npos || vtu.find("</VTKFile>") == std::string::npos ||
        pvd.find("file=\"" + r.second + "\"") == std::string::npos ||
        std::filesystem::exists(directory_ + "/" + r.second + ".tmp"))
      return false;
  }
  return true;
}

template class SPGVtuWriter<2>;
template class SPGVtuWriter<3>;

} // namespace spinesim::meshfree
