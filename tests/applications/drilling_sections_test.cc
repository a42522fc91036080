// Bone block/CT/Cutting coefficients = from density (applications/drilling/drilling_sections):
// K_c and K_t linear in the calibrated density between the Cancellous values at Cancellous
// reference density and the Cortical values at Cortical density, clamped outside; the two
// types must share one size-effect law.

#include "applications/drilling/drilling_sections.h"
#include "base/exceptions.h"

#include <deal.II/base/parameter_handler.h>

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

using namespace spinesim::applications::drilling;

namespace {

BoneSection parse(const std::vector<std::pair<std::string, std::string>>& set) {
  dealii::ParameterHandler prm;
  prm.enter_subsection("Bone block");
  BoneSection::declare(prm);
  for (const auto& [path, value] : set) {
    // "CT/Cutting coefficients" -> subsection CT, entry Cutting coefficients
    const auto slash = path.find('/');
    if (slash == std::string::npos) {
      prm.set(path, value);
      continue;
    }
    prm.enter_subsection(path.substr(0, slash));
    prm.set(path.substr(slash + 1), value);
    prm.leave_subsection();
  }
  BoneSection bone;
  bone.parse(prm);
  prm.leave_subsection();
  return bone;
}

const std::vector<std::pair<std::string, std::string>> from_density = {
    {"CT/Cutting coefficients", "from density"},
    {"CT/Cancellous reference density", "0.2"},
    {"CT/Cortical density", "1.0"},
    {"Cortical/Tangential cutting coefficient", "200"},
    {"Cortical/Thrust cutting coefficient", "300"},
    {"Cancellous/Tangential cutting coefficient", "40"},
    {"Cancellous/Thrust cutting coefficient", "60"}};

// At the anchors the types' values, between them the straight line, outside it clamped; the
// size-effect law is the types' shared one. Exact arithmetic up to round-off.
TEST(DrillingSections, CuttingCoefficientsLinearInDensity) {
  const BoneSection bone = parse(from_density);
  ASSERT_TRUE(bone.cutting_from_density);
  const double tol = 1e-6; // [Pa]: round-off of values ~1e8 Pa is ~1e-8 Pa
  EXPECT_NEAR(bone.cutting_at_density(0.2).tangential, 40e6, tol);
  EXPECT_NEAR(bone.cutting_at_density(1.0).tangential, 200e6, tol);
  EXPECT_NEAR(bone.cutting_at_density(0.6).tangential, 120e6, tol);
  EXPECT_NEAR(bone.cutting_at_density(0.4).thrust, 60e6 + 0.25 * 240e6, tol);
  EXPECT_NEAR(bone.cutting_at_density(-0.5).tangential, 40e6, tol); // clamped below
  EXPECT_NEAR(bone.cutting_at_density(1.9).thrust, 300e6, tol);     // clamped above
  EXPECT_EQ(bone.cutting_at_density(0.6).exponent, bone.cortical.cutting.exponent);
  EXPECT_EQ(bone.cutting_at_density(0.6).reference_chip_thickness,
            bone.cortical.cutting.reference_chip_thickness);
}

TEST(DrillingSections, CuttingFromDensityNeedsOneSizeEffectLaw) {
  auto set = from_density;
  set.push_back({"Cancellous/Chip thickness exponent", "0.2"});
  try {
    parse(set);
    FAIL() << "two size-effect exponents were accepted";
  } catch (const spinesim::InvalidInput& e) {
    EXPECT_EQ(e.where(), "Bone block/Cancellous/Chip thickness exponent");
  }
  set = from_density;
  set.push_back({"Cancellous/Reference chip thickness", "0.1"});
  EXPECT_THROW(parse(set), spinesim::InvalidInput);
  // By type, each type keeps its own law.
  set.push_back({"CT/Cutting coefficients", "by type"});
  EXPECT_FALSE(parse(set).cutting_from_density);
}

TEST(DrillingSections, CuttingFromDensityNeedsOrderedAnchors) {
  auto set = from_density;
  set.push_back({"CT/Cancellous reference density", "1.2"});
  try {
    parse(set);
    FAIL() << "anchors in the wrong order were accepted";
  } catch (const spinesim::InvalidInput& e) {
    EXPECT_EQ(e.where(), "Bone block/CT/Cancellous reference density");
  }
}

} // namespace
