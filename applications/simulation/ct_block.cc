#include "applications/simulation/ct_block.h"

#include "applications/ct/ct_sections.h"
#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::applications {

void CtBlockParameters::declare(dealii::ParameterHandler& prm) {
  fem::CtBoxParameters::declare(
      prm, "the Material section's uniform Young's modulus and density (3-D; the body's "
           "bounding-box top face centre is the block's origin; yield stress and hardening scale "
           "with each cell's modulus)");
}

void CtBlockParameters::parse(const dealii::ParameterHandler& prm) {
  box.parse(prm, "CT block/", ct::resolve_data_file);
}

CtBlock::CtBlock(const CtBlockParameters& parameters, const materials::LawParameters& material,
                 const dealii::BoundingBox<3>& body)
    : box_(parameters.box), material_(material) {
  const auto lower = body.get_boundary_points().first, upper = body.get_boundary_points().second;
  top_centre_ =
      dealii::Point<3>(0.5 * (lower[0] + upper[0]), 0.5 * (lower[1] + upper[1]), upper[2]);
  box_.require_inside(dealii::Point<3>(lower - top_centre_), dealii::Point<3>(upper - top_centre_),
                      "CT block/");
  if (!(material_.youngs_modulus > 0))
    throw InvalidInput("Material/Young's modulus", std::to_string(material_.youngs_modulus),
                       "a positive modulus: the CT block scales the yield stress by E_cell / E");
}

std::shared_ptr<const materials::ConstitutiveLaw> CtBlock::law_at(const dealii::Point<3>& x) const {
  const dealii::Point<3> local(x[0] - top_centre_[0], x[1] - top_centre_[1], x[2] - top_centre_[2]);
  const double rho = box_.density(local);
  if (!std::isfinite(rho)) {
    std::ostringstream where;
    where << "a cell centred at (" << x << ") m";
    throw InvalidInput("CT block/Top centre", where.str() + " lies outside the image",
                       "a block whose body lies inside the image");
  }
  const auto found = laws_.find(rho);
  if (found != laws_.end())
    return found->second;
  materials::LawParameters p = material_;
  const double E = box_.law().modulus(rho); // the law's floors applied
  const double scale = E / material_.youngs_modulus;
  p.youngs_modulus = E;
  p.density = 1000.0 * std::max(rho, box_.law().minimum_density()); // g/cm^3 -> kg/m^3
  p.yield_stress *= scale;
  p.hardening_modulus *= scale;
  p.saturation_stress *= scale;
  std::shared_ptr<const materials::ConstitutiveLaw> law = materials::create_law(p);
  e_min_ = laws_.empty() ? E : std::min(e_min_, E);
  e_max_ = laws_.empty() ? E : std::max(e_max_, E);
  laws_.emplace(rho, law);
  return law;
}

std::string CtBlock::summary() const {
  std::ostringstream s;
  s << "CT block: " << box_.frame_description() << "; " << laws_.size()
    << " densities on this rank, E " << e_min_ / 1e6 << " .. " << e_max_ / 1e6 << " MPa";
  return s.str();
}

} // namespace spinesim::applications
