#include "meshfree/spg/spg_vtu_writer.h"

#include "base/exceptions.h"
#include "fem/materials/tensor_tools.h"
#include "meshfree/bond_loop.h"
#include "meshfree/particle_output.h"

#include <deal.II/base/data_out_base.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
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
  // The stress as six components and the von Mises stress [Pa], in 2-D too (plane strain
  // keeps σ_zz; σ_xz = σ_yz = 0), named as the coupled runs' particle output names them.
  static const char* const names[6] = {"stress_xx", "stress_yy", "stress_zz",
                                       "stress_xy", "stress_yz", "stress_xz"};
  static const unsigned int row[6] = {0, 1, 2, 0, 1, 0}, col[6] = {0, 1, 2, 1, 2, 2};
  for (unsigned int i = 0; i < n; ++i) {
    out.add_particle(p.reference_position(i), p.volume(i));
    out.material_id(i) = p.material_id(i);
  }
  auto& eps = out.add_scalar_field("equivalent_plastic_strain");
  std::vector<std::vector<double>*> stress;
  for (const char* name : names)
    stress.push_back(&out.add_scalar_field(name));
  auto& mises = out.add_scalar_field("von_mises_stress");
  for (unsigned int i = 0; i < n; ++i) {
    out.displacement(i) = uh[i];
    // The velocity is the time derivative of u_h = Σ Ψ_J(X^r_I) d_J (+ a constant shift).
    dealii::Tensor<1, dim> v = rk.self_value[i] * p.velocity(i);
    for_each_bond_of(bonds, i,
                     [&](std::size_t k, unsigned int j) { v += rk.value[k] * p.velocity(j); });
    out.velocity(i) = v;
    out.damage(i) = p.damage(i);
    eps[i] = s.states()[i].equivalent_plastic_strain;
    try {
      const materials::SymTensor2 sigma = s.cauchy_stress(i, p);
      for (unsigned int c = 0; c < 6; ++c)
        (*stress[c])[i] = sigma[row[c]][col[c]];
      mises[i] = materials::von_mises(sigma);
    } catch (const NumericalFailure&) { // an inverted particle: shown as NaN, not as zero
      for (unsigned int c = 0; c < 6; ++c)
        (*stress[c])[i] = std::numeric_limits<double>::quiet_NaN();
      mises[i] = std::numeric_limits<double>::quiet_NaN();
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
