// ParticleSet: generation (lattice, file, lists), flags and named fields.

#include "base/exceptions.h"
#include "meshfree/particle_set.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

using namespace spinesim;
using namespace spinesim::meshfree;

TEST(ParticleSet, Lattice2DCentredCellsWithThickness) {
  const double h = 0.1, T = 0.02;
  const auto p = ParticleSet<2>::lattice(dealii::Point<2>(-1, 0), dealii::Point<2>(1, 0.5), h, T);
  ASSERT_EQ(p.size(), 20u * 5u);
  double total = 0;
  for (unsigned int i = 0; i < p.size(); ++i) {
    // Volume h²T; 1e-15 relative: one rounding in the product.
    EXPECT_NEAR(p.volume(i), h * h * T, 1e-15 * h * h * T);
    total += p.volume(i);
  }
  // The cells tile the box exactly: volume sum = box volume to summation round-off.
  EXPECT_NEAR(total, 2.0 * 0.5 * T, 1e-12 * T);
  // Centred cells: first particle at lo + h/2 (round-off of (k + ½)·dx only).
  EXPECT_NEAR(p.reference_position(0)[0], -1 + 0.5 * h, 1e-14);
  EXPECT_NEAR(p.reference_position(0)[1], 0.5 * h, 1e-14);
  EXPECT_NEAR(p.spacing(0), h, 1e-14);
}

TEST(ParticleSet, Lattice3DAdjustsSpacingToTheBox) {
  // 1/0.3 is not an integer: 3 cells of 1/3 instead, so the box is still tiled exactly.
  const auto p = ParticleSet<3>::lattice(dealii::Point<3>(0, 0, 0), dealii::Point<3>(1, 1, 1), 0.3);
  ASSERT_EQ(p.size(), 27u);
  EXPECT_NEAR(p.volume(13), 1.0 / 27.0, 1e-15);
  EXPECT_NEAR(p.reference_position(13)[2], 0.5, 1e-15); // centre particle of 3×3×3
}

TEST(ParticleSet, FromFileAndMalformedLines) {
  const std::string name = ::testing::TempDir() + "/spinesim_particles.txt";
  {
    std::ofstream out(name);
    out << "# x y z volume\n0 0 0 1e-3\n\n1.5 2 -1 2e-3  # comment\n";
  }
  const auto p = ParticleSet<3>::from_file(name);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p.reference_position(1), dealii::Point<3>(1.5, 2, -1));
  EXPECT_EQ(p.volume(1), 2e-3);
  {
    std::ofstream out(name);
    out << "0 0 1e-3\n0 1 abc\n";
  }
  EXPECT_THROW(ParticleSet<2>::from_file(name), InvalidInput);
  {
    std::ofstream out(name);
    out << "0 0 -1\n";
  }
  EXPECT_THROW(ParticleSet<2>::from_file(name), InvalidInput); // negative volume
  std::remove(name.c_str());
}

TEST(ParticleSet, FromPointsFlagsAndFields) {
  std::vector<dealii::Point<2>> x = {dealii::Point<2>(0, 0), dealii::Point<2>(1, 0)};
  auto p = ParticleSet<2>::from_points(x, {0.5, 0.25}, 2.0);
  p.set_density(4.0);
  EXPECT_EQ(p.mass(1), 1.0);
  EXPECT_NEAR(p.spacing(1), std::sqrt(0.125), 1e-15);
  p.set_fixed(0, 1u);
  EXPECT_TRUE(p.is_fixed(0, 1));
  EXPECT_FALSE(p.is_fixed(0, 0));
  p.set_fixed(1);
  EXPECT_TRUE(p.is_fixed(1, 0) && p.is_fixed(1, 1));
  p.set_fixed(1, false);
  EXPECT_FALSE(p.is_fixed(1));

  auto& theta = p.add_scalar_field("dilatation", 3.0);
  EXPECT_EQ(theta.size(), 2u);
  EXPECT_EQ(&p.add_scalar_field("dilatation"), &theta); // same field, not a new one
  p.add_particle(dealii::Point<2>(2, 0), 0.5);
  EXPECT_EQ(p.scalar_field("dilatation").size(), 3u);
  EXPECT_THROW(p.scalar_field("missing"), InvalidInput);
  EXPECT_THROW(ParticleSet<2>::from_points(x, {1.0}), InvalidInput);
  EXPECT_THROW(ParticleSet<2>::from_points(x, {1.0, 0.0}), InvalidInput);
}
