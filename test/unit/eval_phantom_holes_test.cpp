// Phantom holes (eval/phantom_holes.h): below-ground obstacle clusters next to no object.
#include <gtest/gtest.h>

#include "ladar_perception/eval/phantom_holes.h"

using namespace ladar_perception;

namespace {

// A flat ground of returns every 0.2 m over 24 x 24 m around the sensor (z = -1.73, labelled
// ground), plus extra returns with their labels.
struct Scene {
  std::vector<Eigen::Vector3f> pts;
  std::vector<uint8_t> labels;
  Scene() {
    for (float x = -12.f; x <= 12.f; x += 0.2f) {
      for (float y = -12.f; y <= 12.f; y += 0.2f) add(x, y, -1.73f, kLabelGround);
    }
  }
  void add(float x, float y, float z, uint8_t label) {
    pts.emplace_back(x, y, z);
    labels.push_back(label);
  }
  std::size_t phantoms(std::size_t* clusters, float depth = 0.f) const {
    PackedCloud c;
    c.layout = xyziLayout(static_cast<uint32_t>(pts.size()));
    c.data.assign(static_cast<std::size_t>(c.layout.row_step) * c.layout.height, 0);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      uint8_t* p = c.data.data() + i * c.layout.point_step;
      for (const FieldDesc& f : c.layout.fields) {
        if (f.name == "x") writeField(p, f, pts[i].x());
        if (f.name == "y") writeField(p, f, pts[i].y());
        if (f.name == "z") writeField(p, f, pts[i].z());
      }
    }
    PointCloudView view;
    EXPECT_TRUE(c.view(&view));
    GroundClassification result;
    result.resize(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      result.labels[i] = labels[i];
      result.p_obstacle[i] = labels[i] == kLabelObstacle ? 1.f : 0.f;
    }
    std::vector<eval::PhantomHole> holes;
    *clusters = eval::findPhantomHoles(view, result, eval::PhantomHoleParams(), &holes);
    if (!holes.empty()) {
      EXPECT_NEAR(holes.front().depth, depth, 1e-3f);
    }
    return holes.size();
  }
};

TEST(PhantomHoles, FlatGroundHasNone) {
  Scene s;
  std::size_t clusters = 0;
  EXPECT_EQ(s.phantoms(&clusters), 0u);
  EXPECT_EQ(clusters, 0u);
}

TEST(PhantomHoles, BelowGroundObstacleClusterIsAPhantomHole) {
  Scene s;
  for (float x : {8.f, 8.1f, 8.2f}) s.add(x, 3.f, -1.83f, kLabelObstacle);  // 10 cm deep
  std::size_t clusters = 0;
  EXPECT_EQ(s.phantoms(&clusters, 0.1f), 1u);
  EXPECT_EQ(clusters, 1u);
}

TEST(PhantomHoles, TheFootOfAnObjectIsNoHole) {
  Scene s;
  for (float x : {8.f, 8.1f, 8.2f}) s.add(x, 3.f, -1.83f, kLabelObstacle);
  s.add(8.3f, 3.2f, -1.2f, kLabelObstacle);  // a car's side 0.5 m above the ground
  std::size_t clusters = 0;
  EXPECT_EQ(s.phantoms(&clusters), 0u);
  EXPECT_EQ(clusters, 1u);
}

TEST(PhantomHoles, SingleReturnsShallowOnesAndArtefactsAreNoHoles) {
  Scene s;
  s.add(-6.f, -4.f, -1.85f, kLabelObstacle);   // one return alone
  s.add(5.f, -7.f, -1.75f, kLabelObstacle);    // 2 cm below: within the noise
  s.add(5.1f, -7.f, -1.75f, kLabelObstacle);
  s.add(-3.f, 9.f, -5.f, kLabelObstacle);      // 3 m below: multipath
  s.add(-3.1f, 9.f, -5.f, kLabelObstacle);
  s.add(40.f, 0.f, -1.9f, kLabelObstacle);     // beyond 30 m
  s.add(40.1f, 0.f, -1.9f, kLabelObstacle);
  std::size_t clusters = 0;
  EXPECT_EQ(s.phantoms(&clusters), 0u);
  EXPECT_EQ(clusters, 0u);
}

TEST(PhantomHoles, TheRoadAtACurbsFootIsNotBelowTheSidewalk) {
  Scene s;
  for (float x = -12.f; x <= 12.f; x += 0.2f) {
    for (float y = 5.f; y <= 8.f; y += 0.2f) s.add(x, y, -1.58f, kLabelGround);  // a 15 cm sidewalk
  }
  for (float x : {8.f, 8.1f, 8.2f}) s.add(x, 4.7f, -1.73f, kLabelObstacle);  // road at the curb
  std::size_t clusters = 0;
  EXPECT_EQ(s.phantoms(&clusters), 0u);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
