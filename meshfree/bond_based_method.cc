#include "meshfree/bond_based_method.h"

#include "base/exceptions.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
BondBasedMethod<dim>::BondBasedMethod(const Parameters& parameters,
                                      const ParticleMaterial& material)
    : pd_(parameters, material.youngs_modulus, material.poisson_ratio), prm_(parameters),
      table_(material.table) {
  pd_.set_material_table(material.table);
  check_poisson_ratio(material.poisson_ratio, "");
  checked_nu_.insert(material.poisson_ratio);
}

template <int dim>
void BondBasedMethod<dim>::check_poisson_ratio(double nu, const std::string& law) {
  const auto model = prm_.plane_model;
  const std::string model_name =
      model == PlaneModel::plane_stress ? "plane stress" : "plane strain";
  const double implied = implied_poisson_ratio(model);
  // 1e-6: scenes write 1/3 to ten digits or more; any real mismatch is far larger.
  if (std::abs(nu - implied) <= 1e-6 * implied)
    return;
  const std::string where = dim == 3 ? "3-D" : model_name;
  const std::string whose = law.empty() ? "" : " (particles of law " + law + ")";
  std::ostringstream error;
  error << std::setprecision(3) << 100.0 * shear_modulus_error(model, nu);
  if (!prm_.accept_poisson_mismatch)
    throw InvalidInput(
        "Material/Poisson ratio",
        "= " + std::to_string(nu) + whose +
            ", but bond-based PD represents nu = " + std::to_string(implied) + " in " + where +
            " (pairwise central forces); the shear modulus would be off by " + error.str() + " %",
        "Effects/Particles method = nosb (any Poisson ratio), nu = " + std::to_string(implied) +
            ", or Bond based/Accept Poisson ratio mismatch = true");
  messages_.push_back("bond-based PD represents nu = " + std::to_string(implied) + " in " + where +
                      ", the material" + whose + " has nu = " + std::to_string(nu) +
                      " (accepted): the particles' shear modulus is off by " + error.str() +
                      " % (bulk modulus matched)");
}

template <int dim>
void BondBasedMethod<dim>::declare(dealii::ParameterHandler& prm) {
  BondBasedParameters::declare(prm);
  prm.declare_entry("Accept Poisson ratio mismatch", "false", dealii::Patterns::Bool(),
                    "Bond-based PD represents nu = 1/4 (3-D, plane strain) or 1/3 (plane "
                    "stress): a material with another Poisson ratio is refused unless this is "
                    "true; the log then states the shear-modulus error in percent [-].");
}

template <int dim>
typename BondBasedMethod<dim>::Parameters
BondBasedMethod<dim>::parse_parameters(const dealii::ParameterHandler& section) {
  Parameters p;
  p.parse(section);
  p.accept_poisson_mismatch = section.get_bool("Accept Poisson ratio mismatch");
  return p;
}

template <int dim>
double BondBasedMethod<dim>::shear_modulus_error(PlaneModel model, double nu) {
  // G over the calibration modulus: 3-D G/K = 3(1−2ν)/(2(1+ν)); plane stress
  // G/k' = (1−ν)/(1+ν) with k' = E/(2(1−ν)); plane strain G/k' = 1−2ν with
  // k' = E/(2(1+ν)(1−2ν)).
  const auto ratio = [&](double v) {
    if (dim == 3)
      return 3.0 * (1.0 - 2.0 * v) / (2.0 * (1.0 + v));
    if (model == PlaneModel::plane_stress)
      return (1.0 - v) / (1.0 + v);
    return 1.0 - 2.0 * v;
  };
  return ratio(implied_poisson_ratio(model)) / ratio(nu) - 1.0;
}

template <int dim>
double BondBasedMethod<dim>::implied_poisson_ratio(PlaneModel plane_model) {
  // Pairwise central forces give C12 = C66 (Cauchy relation): ν = 1/4 in 3-D and plane
  // strain, 1/3 in plane stress (Gerstle, Sau & Silling 2007; Silling & Askari 2005).
  if (dim == 2 && plane_model == PlaneModel::plane_stress)
    return 1.0 / 3.0;
  return 0.25;
}

template <int dim>
typename NeighborSearch<dim>::Options BondBasedMethod<dim>::neighbor_options(double spacing) const {
  return pd_.neighbor_options(spacing);
}

template <int dim>
void BondBasedMethod<dim>::initialise(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) {
  // Laws the table gained since the last call: each Poisson ratio is checked once.
  if (table_) {
    if (checked_laws_ > table_->size()) // a checkpoint replaced the table
      checked_laws_ = 0;
    for (; checked_laws_ < table_->size(); ++checked_laws_) {
      const double nu = (*table_)[checked_laws_].poisson_ratio;
      if (checked_nu_.insert(nu).second)
        check_poisson_ratio(nu, table_->law(checked_laws_).name());
    }
  }
  pd_.initialise(particles, bonds);
}

template <int dim>
std::size_t BondBasedMethod<dim>::compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                                 bool allow_breaking) {
  return pd_.compute_forces(particles, bonds, allow_breaking);
}

template <int dim>
std::vector<double> BondBasedMethod<dim>::stiffness_bound(const ParticleSet<dim>&,
                                                          const BondList<dim>& bonds) {
  return pd_.stiffness_bound(bonds);
}

template <int dim>
double BondBasedMethod<dim>::stable_time_step(const ParticleSet<dim>& particles,
                                              const BondList<dim>& bonds, double safety) {
  return pd_.stable_time_step(particles, bonds, safety);
}

template <int dim>
std::vector<double> BondBasedMethod<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                                const BondList<dim>& bonds) const {
  return pd_.strain_energy_density(particles, bonds);
}

template <int dim>
double BondBasedMethod<dim>::strain_energy(const ParticleSet<dim>& particles,
                                           const BondList<dim>& bonds) const {
  return pd_.strain_energy(particles, bonds);
}

template <int dim>
double BondBasedMethod<dim>::bond_energy(const ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds, unsigned int i, std::size_t k,
                                         const std::vector<std::uint8_t>*) const {
  return pd_.bond_energy(particles, bonds, i, k); // a bond's own spring energy, broken or not
}

template <int dim>
void BondBasedMethod<dim>::update_damage(ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds) const {
  pd_.update_damage(particles, bonds);
}

template <int dim>
std::optional<std::vector<dealii::Tensor<1, dim>>>
BondBasedMethod<dim>::driven_reactions(const ParticleSet<dim>& particles,
                                       const BondList<dim>& bonds) const {
  // The splice counts every bond with a free end whole (w = ½ V_i k_ij e², both halves): the
  // force on its driven end is the negative of the force on its free end, as in the kernel
  // (ξ recomputed from the reference positions, meshfree/pmb_force_rows_body.h).
  std::vector<dealii::Tensor<1, dim>> r(particles.size());
  if (driven_.size() != particles.size())
    return r;
  const auto& k = pd_.bond_stiffness();
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (driven_[i])
      continue;
    for (std::size_t b = bonds.begin(i); b < bonds.end(i); ++b) {
      const unsigned int j = bonds.neighbor[b];
      if (!driven_[j] || bonds.broken[b])
        continue;
      const dealii::Tensor<1, dim> y =
          (particles.reference_position(j) - particles.reference_position(i)) +
          (particles.displacement(j) - particles.displacement(i));
      const double l = y.norm();
      r[j] -= (particles.volume(i) * k[b] * ((l - bonds.length[b]) / l)) * y;
    }
  }
  return r;
}

template <int dim>
std::optional<std::vector<double>>
BondBasedMethod<dim>::splice_energy_by_row(const ParticleSet<dim>& particles,
                                           const BondList<dim>& bonds) const {
  // ½ V_i k_ij e² per counted bond: a quarter from each row of a bond between two rows, half
  // from the one row of a bond to a driven particle.
  const auto& k = pd_.bond_stiffness();
  const bool any_driven = driven_.size() == particles.size();
  std::vector<double> E(particles.size(), 0.0);
  for (unsigned int i = 0; i < particles.size(); ++i)
    for (std::size_t b = bonds.begin(i); b < bonds.end(i); ++b) {
      if (bonds.broken[b])
        continue;
      const unsigned int j = bonds.neighbor[b];
      const double e =
          (bonds.xi[b] + (particles.displacement(j) - particles.displacement(i))).norm() -
          bonds.length[b];
      E[i] += (any_driven && driven_[j] ? 0.5 : 0.25) * particles.volume(i) * k[b] * e * e;
    }
  return E;
}

template class BondBasedMethod<2>;
template class BondBasedMethod<3>;

SPINESIM_REGISTER_PARTICLE_METHOD(
    BondBasedMethod, "bond_based", "Bond based",
    "bond-based peridynamics (prototype microelastic brittle, Silling & Askari 2005): "
    "pairwise bonds, critical-stretch fracture; fixed Poisson ratio (1/4 in 3-D and plane "
    "strain, 1/3 in plane stress), no plasticity.")

} // namespace spinesim::meshfree
