// Chains (Table 1) and excluded pairs on hand-made sphere sets with known answers.
#include <doctest/doctest.h>

#include <algorithm>

#include "spherechain/baker/chains.h"

using namespace spherechain::baker;

namespace {

FittedSphere S(Region r, int seq, double x, double y, double rad, uint8_t labels = 0, int level = -1, int column = -1) {
  FittedSphere s;
  s.region = r;
  s.sequence = seq;
  s.center = {x, y, 0};
  s.radius = rad;
  s.labels = labels;
  s.level = level;
  s.column = column;
  return s;
}

// A stick figure: two spheres per limb, two torso levels (bottom D, top T), far apart enough that only
// designed neighbours overlap.
std::vector<FittedSphere> StickFigure() {
  return {
      S(Region::kLeftArm, 0, 3, 10, 0.5), S(Region::kLeftArm, 1, 5, 10, 0.5),          // 0 1
      S(Region::kRightArm, 0, -3, 10, 0.5), S(Region::kRightArm, 1, -5, 10, 0.5),      // 2 3
      S(Region::kLeftLeg, 0, 1, 3, 0.5), S(Region::kLeftLeg, 1, 1, 0, 0.5),            // 4 5
      S(Region::kRightLeg, 0, -1, 3, 0.5), S(Region::kRightLeg, 1, -1, 0, 0.5),        // 6 7
      S(Region::kTorso, 0, 0.8, 6, 0.6, kLabelL | kLabelD, 0, 0),                        // 8
      S(Region::kTorso, 1, -0.8, 6, 0.6, kLabelR | kLabelD, 0, 1),                       // 9
      S(Region::kTorso, 2, 0.8, 9, 0.6, kLabelL | kLabelT, 1, 0),                        // 10
      S(Region::kTorso, 3, -0.8, 9, 0.6, kLabelR | kLabelT, 1, 1),                       // 11
  };
}

std::vector<uint16_t> V(std::initializer_list<uint16_t> v) { return v; }

}  // namespace

TEST_CASE("chains: Table 1 membership on a stick figure") {
  auto chains = BuildChains(StickFigure(), DefaultChainDefs());
  REQUIRE(chains.ok());
  REQUIRE(chains->size() == 6);
  CHECK(chains->at(0).spheres == V({0, 1, 4, 5, 8, 10}));        // ζ0 = R0 ∪ R4L ∪ R2
  CHECK(chains->at(1).spheres == V({2, 3, 6, 7, 9, 11}));        // ζ1 = R1 ∪ R4R ∪ R3
  CHECK(chains->at(2).spheres == V({0, 1, 2, 3, 10, 11}));       // ζ2 = R0 ∪ R4T ∪ R1
  CHECK(chains->at(3).spheres == V({4, 5, 6, 7, 8, 9}));         // ζ3 = R2 ∪ R4D ∪ R3
  CHECK(chains->at(4).spheres == V({0, 1, 6, 7, 9, 10, 11}));    // ζ4 = R0 ∪ R4T ∪ R4R ∪ R3
  CHECK(chains->at(5).spheres == V({2, 3, 4, 5, 8, 10, 11}));    // ζ5 = R1 ∪ R4T ∪ R4L ∪ R2
}

TEST_CASE("chains: bad definitions are rejected with the chain named") {
  auto bad = BuildChains(StickFigure(), {{"mine", {"R0", "R9"}}});
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().code == Error::Code::kConfig);
  CHECK(bad.error().message.find("mine") != std::string::npos);
  CHECK(bad.error().message.find("R9") != std::string::npos);
  CHECK_FALSE(BuildChains(StickFigure(), {}).ok());
  CHECK(BuildChains(StickFigure(), {{"pair", {"R4D"}}}).ok());  // two D spheres: a valid chain
  auto one = BuildChains({S(Region::kLeftArm, 0, 0, 0, 1)}, {{"solo", {"R0"}}});
  CHECK_FALSE(one.ok());
}

TEST_CASE("chains: excluded pairs are sequence neighbours and bind overlaps, nothing else") {
  auto spheres = StickFigure();
  spheres.push_back(S(Region::kLeftArm, 2, 7, 10, 0.5));   // 12: two after sphere 0
  spheres.push_back(S(Region::kLeftArm, 3, 9, 10, 0.5));   // 13: three after sphere 0
  spheres.push_back(S(Region::kTorso, 4, 0.8, 14, 0.6, kLabelL, 4, 0));  // 14: three levels above 8/9
  std::vector<SpherePair> cross;
  const auto ex = ExcludedPairs(spheres, &cross);
  auto has = [&](uint16_t a, uint16_t b) { return std::binary_search(ex.begin(), ex.end(), SpherePair{a, b}); };
  CHECK(has(0, 1));    // left arm sequence
  CHECK(has(4, 5));    // left leg sequence
  CHECK(has(8, 9));    // same torso level
  CHECK(has(8, 10));   // consecutive torso levels, same column
  CHECK(has(9, 10));   // consecutive levels, across columns
  CHECK_FALSE(has(0, 2));   // left arm vs right arm: far apart
  CHECK_FALSE(has(1, 5));   // hand vs foot
  CHECK_FALSE(has(0, 10));  // arm root vs top torso sphere: 2.42 apart > 1.5·(0.5 + 0.6)
  CHECK(has(0, 12));        // i, i+2 in a limb: a joint's neighbourhood
  CHECK_FALSE(has(0, 13));  // i, i+3: a real self-contact when the limb folds
  CHECK(has(12, 13));       // neighbours
  CHECK_FALSE(has(8, 14));  // torso levels 0 and 4
  CHECK(cross.empty());
  CHECK(std::is_sorted(ex.begin(), ex.end()));

  // An arm root within half the radii sum of a torso sphere (a shoulder junction) is excluded.
  auto near = StickFigure();
  near[0].center = {2.2, 9.5, 0};  // 1.49 from sphere 10: > 1.1 (no overlap), < 1.65
  const auto ex_near = ExcludedPairs(near);
  CHECK(std::binary_search(ex_near.begin(), ex_near.end(), SpherePair{0, 10}));

  // Move the left hand onto the left thigh: an arm–leg bind overlap is excluded and flagged.
  spheres[1].center = {1, 3.5, 0};
  cross.clear();
  const auto ex2 = ExcludedPairs(spheres, &cross);
  CHECK(std::binary_search(ex2.begin(), ex2.end(), SpherePair{1, 4}));
  REQUIRE(cross.size() == 1);
  CHECK(cross[0] == SpherePair{1, 4});
}
