// The text reader of coupling checkpoints (coupling/checkpoint_text.h) on hand-written files:
// a version-3 file in 2-D and 3-D and a version-1 file come back field for field (decimal
// numbers read exactly as the same literals compiled), and every one-token edit that save()
// could not have written is InvalidInput naming the file.
#include "base/exceptions.h"
#include "coupling/checkpoint_text.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::coupling {
namespace {

const std::string file = "restart/coupling.txt";

// Two particles of cell 3_1:2 (2-D) at quadrature points 0 and 5 of 8, one broken bond and a
// history record of each kind (own family, bond family).
std::string valid_2d() {
  return "spinesim_coupling 3\n"
         "0.125 2 1 1 0.5 0.25 2\n"
         "3_1:2 4\n"
         "3_1:2 0 1 5 0.001 1850 310.5 0.1 0.2 1e-05 -2 -3e-06 4\n"
         "3_1:2 5 0 0 0.002 1900 311 0.3 0.4 0 0 0 0\n"
         "1 0\n"
         "0 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14\n"
         "1 0 0 0 0 0 0 0 1 0 0 1 0 1 0.5 2\n";
}

CheckpointContents read(const std::string& text, unsigned int dim = 2) {
  std::istringstream in(text);
  return read_checkpoint_text(in, text.size(), dim, 8, file);
}

// Replaces the `token`-th whitespace-separated token of `text` (from 0).
std::string edit(const std::string& text, std::size_t token, const std::string& value) {
  std::istringstream in(text);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;)
    tokens.push_back(t);
  tokens.at(token) = value;
  std::string out;
  for (const auto& t : tokens)
    out += t + " ";
  return out;
}

TEST(CheckpointText, Version3FileReadBack2D) {
  const auto c = read(valid_2d());
  EXPECT_EQ(c.version, 3);
  EXPECT_EQ(c.time, 0.125);
  EXPECT_EQ(c.dissipation, 0.5);
  EXPECT_EQ(c.heat, 0.25);
  ASSERT_EQ(c.converted.size(), 1u);
  EXPECT_EQ(c.converted.at("3_1:2"), 4u);
  ASSERT_EQ(c.particles.size(), 2u);
  const auto& p = c.particles[0];
  EXPECT_EQ(p.cell, "3_1:2");
  EXPECT_EQ(p.point, 0u);
  EXPECT_TRUE(p.free);
  EXPECT_EQ(p.fixed_slots, 5u);
  EXPECT_EQ(p.volume, 0.001);
  EXPECT_EQ(p.density, 1850);
  EXPECT_EQ(p.temperature, 310.5);
  EXPECT_EQ(p.position[0], 0.1);
  EXPECT_EQ(p.position[1], 0.2);
  EXPECT_EQ(p.displacement[0], 1e-05); // u and v interleaved per component, as save() writes
  EXPECT_EQ(p.velocity[0], -2);
  EXPECT_EQ(p.displacement[1], -3e-06);
  EXPECT_EQ(p.velocity[1], 4);
  EXPECT_FALSE(c.particles[1].free);
  EXPECT_EQ(c.particles[1].point, 5u);
  ASSERT_EQ(c.broken.size(), 1u);
  EXPECT_EQ(c.broken[0], std::make_pair(1u, 0u));
  ASSERT_EQ(c.history.size(), 2u);
  EXPECT_EQ(c.history[0].neighbour, 0u);
  EXPECT_EQ(c.history[0].state[0], 1);
  EXPECT_EQ(c.history[0].state[13], 14);
  EXPECT_EQ(c.history[1].particle, 1u);
  EXPECT_EQ(c.history[1].state[13], 2);
  EXPECT_EQ(c.history[1].state[14], 0); // version 3: no fracture damage, so none
}

TEST(CheckpointText, Version4RecordsCarryFractureDamage) {
  // The version-3 file with the fracture damage D_f appended to each history record.
  std::string text = valid_2d();
  text.replace(text.find("spinesim_coupling 3"), 19, "spinesim_coupling 4");
  const std::string end0 = "13 14\n", end1 = "0.5 2\n";
  text.replace(text.find(end0), end0.size(), "13 14 0.25\n");
  text.replace(text.find(end1), end1.size(), "0.5 2 0.75\n");
  const auto c = read(text);
  EXPECT_EQ(c.version, 4);
  ASSERT_EQ(c.history.size(), 2u);
  EXPECT_EQ(c.history[0].state[13], 14);
  EXPECT_EQ(c.history[0].state[14], 0.25);
  EXPECT_EQ(c.history[1].state[14], 0.75);
  // Read as version 3, the records are one number too long: data after the last record.
  text.replace(text.find("spinesim_coupling 4"), 19, "spinesim_coupling 3");
  EXPECT_THROW(read(text), InvalidInput);
}

TEST(CheckpointText, Version3FileReadBack3D) {
  // Cell 0_2:71 (child digits up to 7 in 3-D), one particle, no bonds, no history.
  const std::string text = "spinesim_coupling 3\n1 1 1 0 0 0 0\n0_2:71 1\n"
                           "0_2:71 7 1 0 1e-09 1000 300 1 2 3 4 5 6 7 8 9\n";
  const auto c = read(text, 3);
  ASSERT_EQ(c.particles.size(), 1u);
  EXPECT_EQ(c.particles[0].position[2], 3);
  EXPECT_EQ(c.particles[0].displacement[2], 8);
  EXPECT_EQ(c.particles[0].velocity[2], 9);
  // The same file read as 2-D: "71" is no 2-D child path and the particle has 3 numbers too many.
  EXPECT_THROW(read(text, 2), InvalidInput);
}

TEST(CheckpointText, Version1FileHasNoTotals) {
  const auto c = read("spinesim_coupling 1\n2 0 0 0\n");
  EXPECT_EQ(c.version, 1);
  EXPECT_EQ(c.time, 2);
  EXPECT_EQ(c.dissipation, 0);
  EXPECT_TRUE(c.particles.empty());
}

// Version 9: the short-range pairs born closer (meshfree/short_range_forces.h) after the stick
// points: (i, j, d) with i < j < particles and d > 0 (the fuzz corpus's seed of the same name).
const std::string version9_2d = R"(spinesim_coupling 9
3.7492107755358252e-05 4 2 0 0 0 2 0 2 2 2
12_0: 0
13_0: 0
j2_plasticity 17000000000 0.25 1900 1000000 100000000 0 0 0 0 0.050000000000000003 0.90000000000000002 0
j2_plasticity 110000000000 0.25 1900 1000000 100000000 0 0 0 0 0.050000000000000003 0.90000000000000002 0
12_0: 0 1 0 0.015624999999999993 1900 0 0.3125 0.3125 3.6804245199903115e-05 0.26134705198791824 6.0664884461117579e-05 -0.058384507451835765 0 0 0 0 1625008359571.4294 0
13_0: 0 1 0 0.015624999999999993 1900 0 0.4375 0.3125 6.8381368080629325e-05 1.0217023717342788 5.9386769112802238e-05 -0.071478644261720528 0 0 0 0 2537898629746.5396 0
24_0: 0 1 0 0.015624999999999993 1900 0 0.5625 0.3125 7.84444461212221e-05 0.81036792544963177 6.0254169702474264e-05 0.076008005026730927 0 0 0 0 4807083766667.8574 1
25_0: 0 1 0 0.015624999999999993 1900 0 0.6875 0.3125 7.8807977517515642e-05 0.17987137509010118 5.984704646659513e-05 0.13897768837976154 0 0 0 0 6086404514411.2178 1
0 1 1.0899265367953415e-05 1.7422291323728375e-06 0 6.1761347315329132e-05 0 -7.2660612683282566e-05 1 0 0 1 0 1 8.2357049242151532e-05 82.921180047905096 0
0 2 6.5870361013119099e-06 1.4608632906219152e-06 0 6.516274839800169e-05 0 -7.1749784499313608e-05 1 0 0 1 0 1 8.0934517137967385e-05 81.484908340715762 0
0 1.5e-06 -2.5e-06
2 0 3.0000000000000001e-06
2 3 0.112
0 3 0.2
)";

TEST(CheckpointText, Version9CarriesShortRangeBirths) {
  const auto c = read(version9_2d);
  EXPECT_EQ(c.version, 9);
  ASSERT_EQ(c.sticks.size(), 2u);
  ASSERT_EQ(c.births.size(), 2u);
  EXPECT_EQ(c.births[0].i, 2u);
  EXPECT_EQ(c.births[0].j, 3u);
  EXPECT_EQ(c.births[0].reach, 0.112);
  EXPECT_EQ(c.births[1].i, 0u);
  EXPECT_EQ(c.births[1].reach, 0.2);
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = version9_2d;
    t.replace(t.rfind(from), from.size(), to);
    return t;
  };
  EXPECT_THROW(read(replaced("2 3 0.112", "3 2 0.112")), InvalidInput); // i < j
  EXPECT_THROW(read(replaced("2 3 0.112", "2 4 0.112")), InvalidInput); // j beyond the particles
  EXPECT_THROW(read(replaced("0 3 0.2", "0 3 0")), InvalidInput);       // d > 0
  EXPECT_THROW(read(replaced("0 3 0.2", "0 3 nan")), InvalidInput);
  EXPECT_THROW(read(replaced("0 3 0.2\n", "")), InvalidInput); // the header counts two
  // Read as version 8, the pairs are data after the last record.
  EXPECT_THROW(read(replaced("spinesim_coupling 9", "spinesim_coupling 8")), InvalidInput);
}

TEST(CheckpointText, EditsSaveCannotWriteAreInvalidInput) {
  // Token positions in valid_2d(): 0 tag, 1 version, 2 time, 3-5 counts, 6-7 totals,
  // 8 history count, 9-10 converted cell, 11-23 particle 0, 24-36 particle 1, 37-38 bond,
  // 39-54 and 55-70 history.
  const std::vector<std::pair<std::size_t, std::string>> edits = {
      {0, "spinesim_coupling2"}, // tag
      {1, "4"},                  // a version this code does not know
      {2, "-1"},                 // negative time
      {3, "-1"},                 // a count with a sign: no wrap-around to 2^64 - 1
      {3, "1000"},               // more particles than the 200 bytes can hold
      {4, "1.5"},                // a fractional count
      {6, "1e999"},              // beyond double
      {9, "3_2:2"},              // cell id: two levels announced, one given
      {9, "3_1:4"},              // cell id: child 4 in 2-D
      {12, "8"},                 // quadrature point 8 of 8
      {13, "7"},                 // free flag 0 or 1
      {14, "-5"},                // Dirichlet slots: unsigned
      {15, "0"},                 // zero volume
      {16, "nan"},               // density
      {25, "0"},                 // particle 1 on the site of particle 0
      {37, "0"},                 // a bond of particle 0 with itself
      {38, "2"},                 // a bond to particle 2 of 2
      {39, "2"},                 // history of particle 2 of 2
      {54, "inf"},               // history state
  };
  for (const auto& [token, value] : edits) {
    try {
      read(edit(valid_2d(), token, value));
      ADD_FAILURE() << "token " << token << " = " << value << " accepted";
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.where(), file);
    }
  }
  // Cut before the last number, and one token after the last record.
  const std::string text = valid_2d();
  EXPECT_THROW(read(text.substr(0, text.rfind(' '))), InvalidInput);
  EXPECT_THROW(read(text + "0\n"), InvalidInput);
}

} // namespace
} // namespace spinesim::coupling
