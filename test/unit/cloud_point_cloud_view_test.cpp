#include <gtest/gtest.h>

#include <cmath>

#include "ladar_perception/cloud/point_cloud_view.h"

namespace lp = ladar_perception;

namespace {
lp::PackedCloud makeCloud(const lp::CloudLayout& layout) {
  lp::PackedCloud c;
  c.layout = layout;
  c.data.assign(static_cast<std::size_t>(layout.row_step) * layout.height, 0);
  return c;
}
void setPoint(lp::PackedCloud* c, std::size_t i, float x, float y, float z, int ring = -1) {
  uint8_t* p = c->data.data() + i * c->layout.point_step;
  lp::writeField(p, *lp::findField(c->layout, "x"), x);
  lp::writeField(p, *lp::findField(c->layout, "y"), y);
  lp::writeField(p, *lp::findField(c->layout, "z"), z);
  if (ring >= 0) lp::writeField(p, *lp::findField(c->layout, "ring"), ring);
}
}  // namespace

TEST(PointCloudView, VelodynePacked22ByteLayoutReadsByName) {
  lp::PackedCloud c = makeCloud(lp::velodyneXYZIRTLayout(3));
  EXPECT_EQ(c.layout.point_step, 22u);
  setPoint(&c, 0, 1.f, 2.f, 3.f, 5);
  setPoint(&c, 2, -4.f, 0.5f, -1.5f, 63);
  lp::PointCloudView v;
  std::string err;
  ASSERT_TRUE(c.view(&v, &err)) << err;
  ASSERT_EQ(v.size(), 3u);
  EXPECT_TRUE(v.hasRing());
  EXPECT_EQ(v.xyz(0), Eigen::Vector3f(1.f, 2.f, 3.f));
  EXPECT_EQ(v.ring(0), 5);
  EXPECT_EQ(v.xyz(2), Eigen::Vector3f(-4.f, 0.5f, -1.5f));
  EXPECT_EQ(v.ring(2), 63);
}

TEST(PointCloudView, PclAlignedAndFloat64Layouts) {
  lp::PackedCloud c = makeCloud(lp::pclXYZILayout(2));
  EXPECT_EQ(c.layout.point_step, 32u);
  setPoint(&c, 1, 7.f, 8.f, 9.f);
  lp::PointCloudView v;
  ASSERT_TRUE(c.view(&v));
  EXPECT_FALSE(v.hasRing());
  EXPECT_EQ(v.xyz(1), Eigen::Vector3f(7.f, 8.f, 9.f));

  lp::CloudLayout l;
  l.width = 2;
  lp::appendField(&l, "z", lp::FieldType::kFloat64);
  lp::appendField(&l, "y", lp::FieldType::kFloat64);
  lp::appendField(&l, "x", lp::FieldType::kFloat64);
  lp::appendField(&l, "channel", lp::FieldType::kUInt8);  // Ouster-style ring name
  lp::PackedCloud d = makeCloud(l);
  setPoint(&d, 1, 1.5f, -2.5f, 3.25f);
  lp::writeField(d.data.data() + l.point_step, *lp::findField(l, "channel"), 12);
  ASSERT_TRUE(d.view(&v));
  EXPECT_FALSE(v.packedFloatXYZ());
  EXPECT_EQ(v.xyz(1), Eigen::Vector3f(1.5f, -2.5f, 3.25f));
  ASSERT_TRUE(v.hasRing());
  EXPECT_EQ(v.ring(1), 12);
}

TEST(PointCloudView, OrganisedCloudWithRowPaddingAndNaN) {
  lp::CloudLayout l = lp::xyziLayout(2);
  l.height = 2;
  l.row_step = 2 * l.point_step + 8;  // padded rows
  lp::PackedCloud c = makeCloud(l);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  uint8_t* p = c.data.data() + l.row_step + l.point_step;  // row 1, column 1
  lp::writeField(p, *lp::findField(l, "x"), 4.0);
  lp::writeField(p, *lp::findField(l, "y"), nan);
  lp::writeField(p, *lp::findField(l, "z"), 6.0);
  lp::PointCloudView v;
  ASSERT_TRUE(c.view(&v));
  ASSERT_EQ(v.size(), 4u);
  EXPECT_FLOAT_EQ(v.xyz(3).x(), 4.f);
  EXPECT_TRUE(std::isnan(v.xyz(3).y()));
}

TEST(PointCloudView, RejectsUnreadableLayoutsWithAReason) {
  lp::PointCloudView v;
  std::string err;
  lp::PackedCloud c = makeCloud(lp::xyziLayout(4));
  c.data.resize(c.data.size() - 1);  // truncated
  EXPECT_FALSE(c.view(&v, &err));
  EXPECT_NE(err.find("need"), std::string::npos) << err;

  lp::PackedCloud s = makeCloud(lp::xyziLayout(4));
  s.layout.point_step = 8;  // smaller than the fields
  s.layout.row_step = 32;
  EXPECT_FALSE(s.view(&v, &err));
  EXPECT_NE(err.find("point_step"), std::string::npos) << err;

  lp::CloudLayout no_z;
  no_z.width = 1;
  lp::appendField(&no_z, "x", lp::FieldType::kFloat32);
  lp::appendField(&no_z, "y", lp::FieldType::kFloat32);
  lp::PackedCloud nz = makeCloud(no_z);
  EXPECT_FALSE(nz.view(&v, &err));
  EXPECT_NE(err.find("'z'"), std::string::npos) << err;

  lp::CloudLayout int_xyz;
  int_xyz.width = 1;
  lp::appendField(&int_xyz, "x", lp::FieldType::kInt32);
  lp::appendField(&int_xyz, "y", lp::FieldType::kInt32);
  lp::appendField(&int_xyz, "z", lp::FieldType::kInt32);
  lp::PackedCloud ix = makeCloud(int_xyz);
  EXPECT_FALSE(ix.view(&v, &err));

  lp::PackedCloud be = makeCloud(lp::xyziLayout(1));
  be.layout.is_bigendian = true;
  EXPECT_FALSE(be.view(&v, &err));
}

TEST(PointCloudView, EmptyCloudIsValid) {
  lp::PackedCloud c = makeCloud(lp::xyziLayout(0));
  lp::PointCloudView v;
  ASSERT_TRUE(c.view(&v));
  EXPECT_TRUE(v.empty());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
