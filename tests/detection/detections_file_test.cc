#include "detection/detections_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "types/coco_classes.h"

namespace objmap {
namespace {

/// A fresh file path inside the test binary's temporary directory.
std::string TempPath(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("objmap_detections_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

Detection MakeDetection(const std::string& class_name, float score, BoundingBox2D box) {
  Detection d;
  d.class_id = CocoClassId(class_name);
  d.score = score;
  d.box = box;
  return d;
}

TEST(DetectionsFileTest, RoundTripKeepsEveryField) {
  DetectionsByFrame written;
  written["frame-000500"] = {MakeDetection("cup", 0.8f, {10.f, 20.f, 30.5f, 40.f}),
                             MakeDetection("dining table", 0.25f, {0.f, 100.f, 640.f, 480.f})};
  written["7"] = {};
  const std::string path = TempPath("round_trip.json");
  std::string why;
  ASSERT_TRUE(WriteDetectionsFile(path, written, &why)) << why;
  DetectionsByFrame read;
  ASSERT_TRUE(ReadDetectionsFile(path, &read, &why)) << why;
  ASSERT_EQ(read.size(), 2u);
  ASSERT_EQ(read["frame-000500"].size(), 2u);
  EXPECT_TRUE(read["7"].empty());
  for (std::size_t i = 0; i < 2; ++i) {
    const Detection& a = written["frame-000500"][i];
    const Detection& b = read["frame-000500"][i];
    EXPECT_EQ(a.class_id, b.class_id);
    EXPECT_FLOAT_EQ(a.score, b.score);
    EXPECT_FLOAT_EQ(a.box.x_min, b.box.x_min);
    EXPECT_FLOAT_EQ(a.box.y_min, b.box.y_min);
    EXPECT_FLOAT_EQ(a.box.x_max, b.box.x_max);
    EXPECT_FLOAT_EQ(a.box.y_max, b.box.y_max);
  }
}

TEST(DetectionsFileTest, ScoreDefaultsToOneAndUnderscoresAreAccepted) {
  DetectionsByFrame frames;
  std::string why;
  ASSERT_TRUE(ParseDetectionsJson(
      R"({"frames": {"3": [{"box": [1, 2, 3, 4], "class": "potted_plant"}]}})", &frames, &why))
      << why;
  ASSERT_EQ(frames["3"].size(), 1u);
  EXPECT_EQ(frames["3"][0].class_id, CocoClassId("potted plant"));
  EXPECT_FLOAT_EQ(frames["3"][0].score, 1.f);
}

/// Expects a parse failure whose message contains every one of `needles`.
void ExpectError(const std::string& json, std::initializer_list<const char*> needles) {
  DetectionsByFrame frames;
  std::string why;
  EXPECT_FALSE(ParseDetectionsJson(json, &frames, &why)) << json;
  EXPECT_TRUE(frames.empty());
  for (const char* needle : needles) {
    EXPECT_NE(why.find(needle), std::string::npos) << "'" << needle << "' not in: " << why;
  }
}

TEST(DetectionsFileTest, ErrorsNameFrameAndEntry) {
  const std::string good = R"({"box": [0, 0, 5, 5], "class": "cup", "score": 0.5})";
  ExpectError(R"({"frames": {"f1": [)" + good + R"(, {"box": [0, 0, 5, 5], "class": "unicorn"}]}})",
              {"f1", "entry 1", "unknown class", "unicorn"});
  ExpectError(R"({"frames": {"f2": [{"box": [10, 0, 5, 5], "class": "cup"}]}})",
              {"f2", "entry 0", "x_max < x_min"});
  ExpectError(R"({"frames": {"f3": [{"box": [0, 0, 5], "class": "cup"}]}})",
              {"f3", "entry 0", "box"});
  ExpectError(R"({"frames": {"f4": [{"box": [0, 0, 5, "a"], "class": "cup"}]}})",
              {"f4", "finite numbers"});
  ExpectError(R"({"frames": {"f5": [{"class": "cup"}]}})", {"f5", "missing \"box\""});
  ExpectError(R"({"frames": {"f6": [{"box": [0, 0, 5, 5], "class": "cup", "score": 2}]}})",
              {"f6", "score"});
  ExpectError(R"({"frames": {"f7": {"box": [0, 0, 5, 5]}}})", {"f7", "array"});
  ExpectError(R"({"frame": {}})", {"frames"});
  ExpectError("{not json", {"JSON"});
}

TEST(DetectionsFileTest, MissingFileNamesThePath) {
  DetectionsByFrame frames;
  std::string why;
  EXPECT_FALSE(ReadDetectionsFile("/nonexistent/detections.json", &frames, &why));
  EXPECT_NE(why.find("/nonexistent/detections.json"), std::string::npos) << why;
}

TEST(DetectionsFileTest, WriterRejectsInvalidClassIds) {
  DetectionsByFrame frames;
  frames["0"] = {Detection{}};  // class_id -1
  std::string why;
  EXPECT_FALSE(WriteDetectionsFile(TempPath("bad.json"), frames, &why));
  EXPECT_NE(why.find("invalid class id"), std::string::npos) << why;
}

TEST(DetectionsFileTest, DetectorLooksUpNameThenIndex) {
  DetectionsByFrame frames;
  frames["kitchen/frame-a"] = {MakeDetection("cup", 0.9f, {1.f, 1.f, 2.f, 2.f})};
  frames["12"] = {MakeDetection("tv", 0.7f, {1.f, 1.f, 2.f, 2.f}),
                  MakeDetection("chair", 0.6f, {3.f, 3.f, 4.f, 4.f})};
  DetectionsFileConfig config;
  config.path = TempPath("lookup.json");
  std::string why;
  ASSERT_TRUE(WriteDetectionsFile(config.path, frames, &why)) << why;
  std::unique_ptr<Detector> detector = MakeDetectionsFileDetector(config, &why);
  ASSERT_NE(detector, nullptr) << why;
  EXPECT_EQ(detector->Name(), "file");

  RgbdFrame frame;
  frame.name = "kitchen/frame-a";
  frame.frame_index = 12;
  std::vector<Detection> detections;
  ASSERT_TRUE(detector->Detect(frame, &detections, &why)) << why;
  ASSERT_EQ(detections.size(), 1u);  // the name wins over the index
  EXPECT_EQ(detections[0].class_id, CocoClassId("cup"));

  frame.name = "unlisted";
  ASSERT_TRUE(detector->Detect(frame, &detections, &why)) << why;
  EXPECT_EQ(detections.size(), 2u);

  frame.frame_index = 13;
  ASSERT_TRUE(detector->Detect(frame, &detections, &why)) << why;
  EXPECT_TRUE(detections.empty());

  config.require_every_frame = true;
  detector = MakeDetectionsFileDetector(config, &why);
  ASSERT_NE(detector, nullptr) << why;
  EXPECT_FALSE(detector->Detect(frame, &detections, &why));
  EXPECT_NE(why.find("unlisted"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
