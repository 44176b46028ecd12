// Negative obstacles scored per hole (evaluateHoles in ground_evaluation.h).
#include <gtest/gtest.h>

#include "ladar_perception/eval/ground_evaluation.h"

using namespace ladar_perception;

namespace {

// Calls every return one label.
class ConstantModel : public GroundModel {
 public:
  explicit ConstantModel(uint8_t label) : label_(label) {}
  std::string name() const override { return "constant"; }
  void classify(const PointCloudView& view, const SensorPose&, GroundClassification* out) override {
    out->resize(view.size());
    for (std::size_t i = 0; i < view.size(); ++i) {
      out->labels[i] = label_;
      out->p_obstacle[i] = label_ == kLabelObstacle ? 1.f : 0.f;
    }
  }

 private:
  uint8_t label_;
};

TEST(HoleScore, PotholesWorldHolesPassTheSizeAndDepthTests) {
  sim::World world;
  std::string error;
  ASSERT_TRUE(sim::makeStandardWorld("potholes", 1, &world, &error)) << error;
  std::vector<int> cell_hole;
  const std::vector<WorldHole> holes = worldHoles(world, HoleParams(), &cell_hole);
  ASSERT_GE(holes.size(), 10u);
  for (const WorldHole& h : holes) {
    EXPECT_GE(h.across, 0.25 - 1e-9);
    EXPECT_GE(h.depth, 0.05 - 1e-6);
    EXPECT_EQ(cell_hole[h.cells.front()], &h - holes.data());
  }
  // Stricter size tests keep fewer holes.
  HoleParams strict;
  strict.min_depth = 0.2;
  EXPECT_LT(worldHoles(world, strict, &cell_hole).size(), holes.size());
}

TEST(HoleScore, FoundWhenAReturnInsideIsCalledObstacle) {
  std::string error;
  HoleScore all, none;
  ConstantModel obstacle(kLabelObstacle), ground(kLabelGround);
  ASSERT_TRUE(evaluateHoles("potholes", &obstacle, sim::NoiseProfile::kTable41, 2, 1, HoleParams(), &all, &error));
  ASSERT_TRUE(evaluateHoles("potholes", &ground, sim::NoiseProfile::kTable41, 2, 1, HoleParams(), &none, &error));
  EXPECT_GT(all.seen, 0u);
  EXPECT_EQ(all.found, all.seen);
  EXPECT_DOUBLE_EQ(all.recall(), 1.0);
  EXPECT_EQ(none.seen, all.seen);
  EXPECT_EQ(none.found, 0u);
  EXPECT_EQ(all.seen_by_range[0] + all.seen_by_range[1] + all.seen_by_range[2], all.seen);
  // A world without holes scores none.
  HoleScore flat;
  ASSERT_TRUE(evaluateHoles("flat", &obstacle, sim::NoiseProfile::kTable41, 1, 1, HoleParams(), &flat, &error));
  EXPECT_EQ(flat.holes, 0u);
  EXPECT_EQ(flat.seen, 0u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
