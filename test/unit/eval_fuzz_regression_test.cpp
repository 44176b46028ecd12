// Replays the committed inputs of the real-data readers' fuzz target (fuzz_real_data: KITTI
// .bin, SemanticKITTI .label, ground masks, scoring, frame ranges, labelled folders) through the
// entry point scripts/fuzz builds with libFuzzer.
#include <gtest/gtest.h>

#define LADAR_FUZZ_ENTRY ladarFuzzRealData
#include "../fuzz/fuzz_real_data.cpp"
#undef LADAR_FUZZ_ENTRY
#include "../fuzz/fuzz_replay.h"

TEST(FuzzRegression, RealDataReadersAndScoring) {
  EXPECT_GE(ladar_perception::fuzz::replay("fuzz_real_data", &ladarFuzzRealData, false), 4);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
