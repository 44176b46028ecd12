// The real-data scoring of ground_eval --semantickitti on tiny hand-made labelled scans with
// known counts, and the SemanticKITTI-layout readers.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "ladar_perception/eval/real_ground_eval.h"
#include "ladar_perception/eval/semantic_kitti.h"
#include "ladar_perception/ground/ground_model.h"

using namespace ladar_perception;
using namespace ladar_perception::eval;

namespace {

struct HandScan {
  std::vector<float> xyzi;        // 4 floats per return
  std::vector<uint16_t> classes;
  std::vector<uint8_t> called;    // 1 = the model called it ground
  void add(float x, float y, float z, uint16_t c, bool ground) {
    xyzi.insert(xyzi.end(), {x, y, z, 0.f});
    classes.push_back(c);
    called.push_back(ground);
  }
  PackedCloud cloud() const {
    PackedCloud out;
    out.layout = xyziLayout(static_cast<uint32_t>(classes.size()));
    out.data.resize(xyzi.size() * 4);
    std::memcpy(out.data.data(), xyzi.data(), out.data.size());
    return out;
  }
};

// 10 road (8 called ground), 4 terrain (1 called ground), 5 car (1 called ground),
// 3 building (0), 6 vegetation (2 low, 4 high; 3 called ground: both low and one high),
// 2 unlabeled (1 called ground), 1 outlier (called ground). Sensor height 1.7: low < -1.275.
HandScan makeHandScan() {
  HandScan s;
  namespace sk = semantic_kitti;
  for (int i = 0; i < 10; ++i) s.add(2.f + i, 0.f, -1.7f, sk::kRoad, i < 8);       // 2..11 m
  for (int i = 0; i < 4; ++i) s.add(0.f, 25.f + i, -1.6f, sk::kTerrain, i == 0);   // 25..28 m
  for (int i = 0; i < 5; ++i) s.add(7.f, 1.f, -1.f + 0.2f * i, sk::kCar, i == 0);  // ~7 m
  for (int i = 0; i < 3; ++i) s.add(60.f, 0.f, 2.f, sk::kBuilding, false);         // 60 m
  s.add(3.f, 3.f, -1.5f, sk::kVegetation, true);   // low, called ground
  s.add(3.f, 3.f, -1.4f, sk::kVegetation, true);   // low, called ground
  s.add(3.f, 3.f, -1.0f, sk::kVegetation, true);   // high, called ground
  for (int i = 0; i < 3; ++i) s.add(3.f, 3.f, 0.5f, sk::kVegetation, false);
  s.add(1.f, 1.f, -1.7f, sk::kUnlabeled, true);
  s.add(1.f, 1.f, -1.7f, sk::kUnlabeled, false);
  s.add(1.f, 1.f, -1.7f, sk::kOutlier, true);
  return s;
}

}  // namespace

TEST(SemanticKittiScore, ProtocolACountsByHand) {
  const HandScan s = makeHandScan();
  const PackedCloud cloud = s.cloud();
  PointCloudView view;
  ASSERT_TRUE(cloud.view(&view));
  RealGroundScore score;
  scoreGroundScan(view, s.classes.data(), s.called.data(), 1.7f, GroundProtocol::kA, &score);
  EXPECT_EQ(score.scans, 1u);
  EXPECT_EQ(score.true_ground, 9u);    // 8 road + 1 terrain
  EXPECT_EQ(score.missed_ground, 5u);  // 2 road + 3 terrain
  EXPECT_EQ(score.false_ground, 1u);   // 1 car; vegetation, unlabeled, outlier not scored
  EXPECT_EQ(score.true_obstacle, 7u);  // 4 car + 3 building
  EXPECT_EQ(score.dropped_ground, 0u);
  EXPECT_DOUBLE_EQ(score.precision(), 9.0 / 10.0);
  EXPECT_DOUBLE_EQ(score.recall(), 9.0 / 14.0);
  EXPECT_DOUBLE_EQ(score.f1(), 2.0 * 0.9 * (9.0 / 14.0) / (0.9 + 9.0 / 14.0));
  EXPECT_DOUBLE_EQ(score.obstacleRecall(), 7.0 / 8.0);
  ASSERT_EQ(score.classes.count(semantic_kitti::kTerrain), 1u);
  EXPECT_EQ(score.classes.at(semantic_kitti::kTerrain).points, 4u);
  EXPECT_EQ(score.classes.at(semantic_kitti::kTerrain).called_ground, 1u);
  EXPECT_EQ(score.classes.at(semantic_kitti::kCar).called_ground, 1u);
  EXPECT_EQ(score.classes.count(semantic_kitti::kVegetation), 0u);
  EXPECT_EQ(score.classes.count(semantic_kitti::kUnlabeled), 0u);
  // Range bands: road at 2..11 m: 2,3,4 in 0-5 (3), 5..9 in 5-10 (5), 10, 11 in 10-20 (2).
  EXPECT_EQ(score.bands[0].ground, 3u);
  EXPECT_EQ(score.bands[1].ground, 5u);
  EXPECT_EQ(score.bands[2].ground, 2u);
  EXPECT_EQ(score.bands[2].ground_called_ground, 0u);  // road 10 and 11 m were missed
  EXPECT_EQ(score.bands[3].ground, 4u);                // terrain 25..28 m
  EXPECT_EQ(score.bands[1].non_ground, 5u);            // the car
  EXPECT_EQ(score.bands[1].non_ground_called_ground, 1u);
  EXPECT_EQ(score.bands[5].non_ground, 3u);            // the building at 60 m
}

TEST(SemanticKittiScore, ProtocolBVegetationAndDroppedReturns) {
  const HandScan s = makeHandScan();
  const PackedCloud cloud = s.cloud();
  PointCloudView view;
  ASSERT_TRUE(cloud.view(&view));
  RealGroundScore score;
  scoreGroundScan(view, s.classes.data(), s.called.data(), 1.7f, GroundProtocol::kB, &score);
  EXPECT_EQ(score.true_ground, 11u);   // + 2 low vegetation
  EXPECT_EQ(score.missed_ground, 5u);
  EXPECT_EQ(score.false_ground, 2u);   // car + high vegetation called ground
  EXPECT_EQ(score.true_obstacle, 10u); // + 3 high vegetation
  EXPECT_EQ(score.dropped_ground, 2u); // unlabeled + outlier called ground
  EXPECT_DOUBLE_EQ(score.precision(), 11.0 / 13.0);
  EXPECT_EQ(score.classes.at(semantic_kitti::kVegetation).points, 6u);
}

TEST(SemanticKittiScore, SumsOverScansAndEmptyIsPerfect) {
  RealGroundScore empty;
  EXPECT_DOUBLE_EQ(empty.precision(), 1.0);
  EXPECT_DOUBLE_EQ(empty.recall(), 1.0);
  const HandScan s = makeHandScan();
  const PackedCloud cloud = s.cloud();
  PointCloudView view;
  ASSERT_TRUE(cloud.view(&view));
  RealGroundScore one, two;
  scoreGroundScan(view, s.classes.data(), s.called.data(), 1.7f, GroundProtocol::kA, &one);
  two.add(one);
  two.add(one);
  EXPECT_EQ(two.scans, 2u);
  EXPECT_EQ(two.true_ground, 18u);
  EXPECT_EQ(two.classes.at(semantic_kitti::kRoad).points, 20u);
  EXPECT_EQ(two.bands[3].ground, 8u);
  EXPECT_DOUBLE_EQ(two.f1(), one.f1());
}

TEST(SemanticKittiScore, FrameRanges) {
  long a = 0, b = 0;
  EXPECT_TRUE(parseFrameRange("3:7", &a, &b));
  EXPECT_EQ(a, 3);
  EXPECT_EQ(b, 7);
  EXPECT_TRUE(parseFrameRange("12", &a, &b));
  EXPECT_EQ(a, 12);
  EXPECT_EQ(b, 12);
  EXPECT_TRUE(parseFrameRange(":4", &a, &b));
  EXPECT_EQ(a, 0);
  EXPECT_EQ(b, 4);
  EXPECT_TRUE(parseFrameRange("5:", &a, &b));
  EXPECT_EQ(a, 5);
  EXPECT_FALSE(parseFrameRange("7:3", &a, &b));
  EXPECT_FALSE(parseFrameRange(":", &a, &b));
  EXPECT_FALSE(parseFrameRange("x", &a, &b));
  EXPECT_FALSE(parseFrameRange("", &a, &b));
}

namespace {

void writeBytes(const std::string& path, const void* data, std::size_t n) {
  std::ofstream f(path, std::ios::binary);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
}

// A SemanticKITTI-layout folder with frames 000001 and 000003 labelled, 000002 without labels.
std::string makeLayoutFolder(const HandScan& s) {
  char tmpl[] = "/tmp/ladar_semkitti_XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::mkdir((dir + "/velodyne").c_str(), 0755);
  ::mkdir((dir + "/labels").c_str(), 0755);
  std::vector<uint32_t> labels;
  for (uint16_t c : s.classes) labels.push_back((7u << 16) | c);  // instance id in the upper half
  for (const char* f : {"000001", "000002"}) {
    writeBytes(dir + "/velodyne/" + f + ".bin", s.xyzi.data(), s.xyzi.size() * 4);
  }
  // 000003 is a link stored as a text file naming its target, as git writes one without links.
  ::mkdir((dir + "/raw").c_str(), 0755);
  writeBytes(dir + "/raw/000003.bin", s.xyzi.data(), s.xyzi.size() * 4);
  const std::string stub = "../raw/000003.bin";
  writeBytes(dir + "/velodyne/000003.bin", stub.data(), stub.size());
  writeBytes(dir + "/labels/000001.label", labels.data(), labels.size() * 4);
  writeBytes(dir + "/labels/000003.label", labels.data(), labels.size() * 4);
  ::mkdir((dir + "/masks").c_str(), 0755);
  writeBytes(dir + "/masks/000001.mask", s.called.data(), s.called.size());
  writeBytes(dir + "/masks/000003.mask", s.called.data(), s.called.size());
  return dir;
}

}  // namespace

TEST(SemanticKittiFiles, ListsLabelledFramesAndReadsClasses) {
  const HandScan s = makeHandScan();
  const std::string dir = makeLayoutFolder(s);
  std::vector<LabelledFrameFiles> files;
  std::string error;
  ASSERT_TRUE(listLabelledFrames(dir, 0, -1, &files, &error)) << error;
  ASSERT_EQ(files.size(), 2u);  // 000002 has no label
  EXPECT_EQ(files[0].name, "000001");
  EXPECT_EQ(files[1].name, "000003");
  EXPECT_EQ(files[1].scan_path, dir + "/velodyne/../raw/000003.bin");  // link stub followed
  ASSERT_TRUE(listLabelledFrames(dir, 2, 5, &files, &error)) << error;
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].name, "000003");
  EXPECT_FALSE(listLabelledFrames(dir, 2, 2, &files, &error));
  EXPECT_NE(error.find("no scan with a label"), std::string::npos) << error;
  EXPECT_FALSE(listLabelledFrames(dir + "/nothing", 0, -1, &files, &error));
  EXPECT_NE(error.find("velodyne"), std::string::npos) << error;

  std::vector<uint16_t> classes;
  ASSERT_TRUE(readSemanticClasses(dir + "/labels/000001.label", s.classes.size(), &classes, &error)) << error;
  EXPECT_EQ(classes, s.classes);  // instance ids stripped
  EXPECT_FALSE(readSemanticClasses(dir + "/labels/000001.label", s.classes.size() + 1, &classes, &error));
  EXPECT_NE(error.find("labels for a scan of"), std::string::npos) << error;

  // Mask files of another program score as the hand-made prediction does, frame by frame.
  ASSERT_TRUE(listLabelledFrames(dir, 0, -1, &files, &error));
  std::vector<LabelledFrame> frames;
  ASSERT_TRUE(loadLabelledFrames(files, &frames, &error)) << error;
  MethodScore masks;
  ASSERT_TRUE(scoreMaskFiles("other", dir + "/masks", frames, 1.7f, &masks, &error)) << error;
  EXPECT_EQ(masks.a().scans, 2u);
  EXPECT_EQ(masks.a().true_ground, 18u);
  EXPECT_EQ(masks.b().dropped_ground, 4u);
  ASSERT_EQ(masks.frame_f1[0].size(), 2u);
  EXPECT_DOUBLE_EQ(masks.frame_f1[0][0], masks.a().f1());
  EXPECT_FALSE(scoreMaskFiles("other", dir + "/labels", frames, 1.7f, &masks, &error));

  // A ground model runs over the frames with one time per frame; the tables name it.
  std::unique_ptr<GroundModel> model = makeGroundModel("vertical_scan", &error);
  ASSERT_TRUE(model);
  MethodScore modelled;
  std::vector<std::vector<uint8_t>> called;
  ASSERT_TRUE(scoreGroundModel(model.get(), frames, SensorPose::fromHeight(1.7f), &modelled, &error, &called)) << error;
  EXPECT_EQ(modelled.ms.size(), 2u);
  EXPECT_EQ(called.size(), 2u);
  EXPECT_EQ(modelled.a().true_ground + modelled.a().missed_ground, 28u);
  const std::string table = realGroundSummaryTable({modelled, masks});
  EXPECT_NE(table.find("| vertical_scan | A | 2 |"), std::string::npos) << table;
  EXPECT_NE(table.find("| other | B | 2 |"), std::string::npos) << table;
  EXPECT_NE(realGroundClassTable({masks}).find("terrain (ground: recall) | 8 | 25.00% |"), std::string::npos)
      << realGroundClassTable({masks});
  EXPECT_NE(realGroundRangeTable({masks}).find("0-5 m"), std::string::npos);
  std::system(("rm -rf " + dir).c_str());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
