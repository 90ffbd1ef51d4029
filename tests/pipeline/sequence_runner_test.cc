// The whole pipeline on real data: redkitchen frames through the real detector and the mapper.
#include "pipeline/sequence_runner.h"

#include <gtest/gtest.h>

#include <map>

#include "detection/centernet_detector.h"
#include "test_data.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

const std::string kModelPath = std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb";

TEST(SequenceRunner, MapsChairsAndCupsOfRedkitchen) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  OBJMAP_REQUIRE_PATH(kModelPath);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  CenterNetConfig detector_config;
  detector_config.model_path = kModelPath;
  auto detector = MakeCenterNetDetector(detector_config, &why);
  ASSERT_NE(detector, nullptr) << why;

  // Frames 230-329 look at the table from one side: cups on it, chairs around it.
  SequenceRunConfig run;
  run.first_frame = 230;
  run.max_frames = 100;
  const MapperConfig mapper_config;
  Mapper mapper{mapper_config};
  SequenceRunReport report;
  std::size_t progress_calls = 0;
  ASSERT_TRUE(RunSequence(
      *reader, detector.get(), &mapper, run,
      [&](std::size_t, std::size_t total, std::size_t) { progress_calls += total == 100 ? 1 : 0; },
      &report, &why))
      << why;
  EXPECT_EQ(report.frames_read, 100u);
  EXPECT_EQ(progress_calls, 100u);
  EXPECT_TRUE(report.skipped.empty());
  EXPECT_GE(report.keyframes.size(), 4u);
  EXPECT_EQ(report.keyframes.size(), mapper.num_keyframes());

  std::map<std::string, int> counts;
  for (const InventoryEntry& entry : mapper.Inventory()) {
    counts[std::string(CocoClassName(entry.class_id))] = entry.count;
  }
  EXPECT_GE(counts["cup"], 1);
  EXPECT_GE(counts["chair"], 1);
  EXPECT_LE(counts["dining table"], 1);  // never a duplicated table
}

TEST(SequenceRunner, RejectsAnEmptySelection) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  SequenceRunConfig run;
  run.first_frame = 5000;
  const MapperConfig mapper_config;
  Mapper mapper{mapper_config};
  SequenceRunReport report;
  EXPECT_FALSE(RunSequence(*reader, nullptr, &mapper, run, nullptr, &report, &why));
  EXPECT_NE(why.find("no frames selected: first frame 5000 of 1000"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
