#include "detection/centernet_detector.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "test_data.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

const std::string kModelPath = std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb";

std::string ColorPath(int index) {
  char name[64];
  std::snprintf(name, sizeof(name), "redkitchen/frame-%06d.color.jpg", index);
  return testing::SharedDataPath(name);
}

bool LoadFrame(int index, RgbdFrame* frame) {
  const cv::Mat bgr = cv::imread(ColorPath(index), cv::IMREAD_COLOR);
  if (bgr.empty()) return false;
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  frame->frame_index = index;
  frame->name = ColorPath(index);
  frame->color.width = rgb.cols;
  frame->color.height = rgb.rows;
  frame->color.rgb.assign(rgb.data, rgb.data + rgb.total() * 3);
  return true;
}

std::unique_ptr<Detector> MakeDetector(float score_threshold) {
  CenterNetConfig config;
  config.model_path = kModelPath;
  config.score_threshold = score_threshold;
  std::string why;
  std::unique_ptr<Detector> detector = MakeCenterNetDetector(config, &why);
  EXPECT_NE(detector, nullptr) << why;
  return detector;
}

/// Number of detections of a class at or above a score.
int Count(const std::vector<Detection>& detections, const std::string& class_name, float score) {
  return static_cast<int>(
      std::count_if(detections.begin(), detections.end(), [&](const Detection& d) {
        return CocoClassName(d.class_id) == class_name && d.score >= score;
      }));
}

/// Best-scoring detection of a class, or nullptr.
const Detection* Best(const std::vector<Detection>& detections, const std::string& class_name) {
  const Detection* best = nullptr;
  for (const Detection& d : detections) {
    if (CocoClassName(d.class_id) == class_name && (best == nullptr || d.score > best->score)) {
      best = &d;
    }
  }
  return best;
}

/// Best score of a class among the detections, 0 when absent.
float BestScore(const std::vector<Detection>& detections, const std::string& class_name) {
  const Detection* best = Best(detections, class_name);
  return best == nullptr ? 0.f : best->score;
}

void Print(const char* title, const std::vector<Detection>& detections) {
  std::printf("%s: %zu detections\n", title, detections.size());
  for (const Detection& d : detections) {
    std::printf("  %-14s %.3f  [%.0f %.0f %.0f %.0f]\n",
                std::string(CocoClassName(d.class_id)).c_str(), d.score, d.box.x_min, d.box.y_min,
                d.box.x_max, d.box.y_max);
  }
}

TEST(CenterNetDetectorTest, RejectsBadConfigAndMissingModel) {
  CenterNetConfig config;
  std::string why;
  config.input_size = 500;
  EXPECT_EQ(MakeCenterNetDetector(config, &why), nullptr);
  EXPECT_NE(why.find("input_size"), std::string::npos) << why;
  config = CenterNetConfig();
  config.tiles_per_side = 0;
  EXPECT_EQ(MakeCenterNetDetector(config, &why), nullptr);
  EXPECT_NE(why.find("tiles_per_side"), std::string::npos) << why;
  config = CenterNetConfig();
  config.tile_overlap = 0.95f;
  EXPECT_EQ(MakeCenterNetDetector(config, &why), nullptr);
  EXPECT_NE(why.find("tile_overlap"), std::string::npos) << why;
  config = CenterNetConfig();
  config.model_path = "/nonexistent/centernet.pb";
  EXPECT_EQ(MakeCenterNetDetector(config, &why), nullptr);
  EXPECT_NE(why.find("/nonexistent/centernet.pb"), std::string::npos) << why;
}

// The converted graph fixes its upsampling sizes: another input size fails when the model is
// loaded, not on every frame.
TEST(CenterNetDetectorTest, AnInputSizeTheGraphDoesNotTakeIsRefusedAtLoad) {
  OBJMAP_REQUIRE_PATH(kModelPath);
  CenterNetConfig config;
  config.model_path = kModelPath;
  config.input_size = 768;
  std::string why;
  EXPECT_EQ(MakeCenterNetDetector(config, &why), nullptr);
  EXPECT_NE(why.find("does not run at input_size 768"), std::string::npos) << why;
  config.input_size = 512;
  EXPECT_NE(MakeCenterNetDetector(config, &why), nullptr) << why;
}

TEST(CenterNetDetectorTest, EmptyImageIsAnErrorNamingTheFrame) {
  OBJMAP_REQUIRE_PATH(kModelPath);
  std::unique_ptr<Detector> detector = MakeDetector(0.15f);
  ASSERT_NE(detector, nullptr);
  RgbdFrame frame;
  frame.name = "empty-frame";
  std::vector<Detection> detections;
  std::string why;
  EXPECT_FALSE(detector->Detect(frame, &detections, &why));
  EXPECT_NE(why.find("empty-frame"), std::string::npos) << why;
}

TEST(CenterNetDetectorTest, ThresholdsAndBoxesAreRespected) {
  OBJMAP_REQUIRE_PATH(kModelPath);
  OBJMAP_REQUIRE_PATH(ColorPath(500));
  RgbdFrame frame;
  ASSERT_TRUE(LoadFrame(500, &frame));
  std::size_t previous_count = 0;
  for (float threshold : {0.15f, 0.35f}) {
    std::unique_ptr<Detector> detector = MakeDetector(threshold);
    ASSERT_NE(detector, nullptr);
    std::vector<Detection> detections;
    std::string why;
    ASSERT_TRUE(detector->Detect(frame, &detections, &why)) << why;
    Print(threshold < 0.2f ? "frame 500, threshold 0.15" : "frame 500, threshold 0.35", detections);
    for (std::size_t i = 0; i < detections.size(); ++i) {
      const Detection& d = detections[i];
      EXPECT_GE(d.score, threshold);
      if (i > 0) {
        EXPECT_LE(d.score, detections[i - 1].score);
      }
      EXPECT_GE(d.box.x_min, 0.f);
      EXPECT_LE(d.box.x_max, static_cast<float>(frame.color.width));
      EXPECT_GE(d.box.y_min, 0.f);
      EXPECT_LE(d.box.y_max, static_cast<float>(frame.color.height));
      EXPECT_GT(d.box.Area(), 0.f);
    }
    if (threshold > 0.2f) {
      EXPECT_LT(detections.size(), previous_count);  // a higher threshold keeps fewer
    }
    previous_count = detections.size();
  }
}

// Frame 500 of 7-Scenes redkitchen shows a table with two cups, chairs around it and a monitor
// in the top-right corner (checked by eye). Score bounds leave ~0.1 of margin below what the
// converted model gives, so small numeric differences between OpenCV builds do not matter.
TEST(CenterNetDetectorTest, FindsKitchenObjectsOnRedKitchenFrame500) {
  OBJMAP_REQUIRE_PATH(kModelPath);
  OBJMAP_REQUIRE_PATH(ColorPath(500));
  RgbdFrame frame;
  ASSERT_TRUE(LoadFrame(500, &frame));
  std::unique_ptr<Detector> detector = MakeDetector(CenterNetConfig().score_threshold);
  ASSERT_NE(detector, nullptr);
  std::vector<Detection> detections;
  std::string why;
  ASSERT_TRUE(detector->Detect(frame, &detections, &why)) << why;
  EXPECT_GE(BestScore(detections, "chair"), 0.45f);
  EXPECT_GE(BestScore(detections, "cup"), 0.45f);
  EXPECT_GE(BestScore(detections, "tv"), 0.35f);
  EXPECT_GE(Count(detections, "chair", 0.25f), 2);
  EXPECT_GE(Count(detections, "cup", 0.3f), 2);
  // The white cup left of the books is centred near pixel (142, 271), about 40 x 45 px.
  const Detection* cup = Best(detections, "cup");
  ASSERT_NE(cup, nullptr);
  EXPECT_NEAR(0.5f * (cup->box.x_min + cup->box.x_max), 142.f, 20.f);
  EXPECT_NEAR(0.5f * (cup->box.y_min + cup->box.y_max), 271.f, 20.f);
  EXPECT_NEAR(cup->box.Width(), 40.f, 20.f);
  EXPECT_NEAR(cup->box.Height(), 45.f, 20.f);
}

// Tiles add passes over parts of the image scaled up: what the whole image found stays (at the
// same or a better score), boxes stay inside the image and in descending score order.
TEST(CenterNetDetectorTest, TiledInferenceKeepsTheWholeImagesObjects) {
  OBJMAP_REQUIRE_PATH(kModelPath);
  OBJMAP_REQUIRE_PATH(ColorPath(500));
  RgbdFrame frame;
  ASSERT_TRUE(LoadFrame(500, &frame));
  CenterNetConfig config;
  config.model_path = kModelPath;
  std::string why;
  std::unique_ptr<Detector> whole = MakeCenterNetDetector(config, &why);
  ASSERT_NE(whole, nullptr) << why;
  config.tiles_per_side = 2;
  std::unique_ptr<Detector> tiled = MakeCenterNetDetector(config, &why);
  ASSERT_NE(tiled, nullptr) << why;
  std::vector<Detection> plain, with_tiles;
  ASSERT_TRUE(whole->Detect(frame, &plain, &why)) << why;
  ASSERT_TRUE(tiled->Detect(frame, &with_tiles, &why)) << why;
  Print("frame 500, 2 x 2 tiles", with_tiles);
  for (const char* name : {"chair", "cup", "tv"}) {
    EXPECT_GE(BestScore(with_tiles, name), BestScore(plain, name)) << name;
  }
  for (std::size_t i = 0; i < with_tiles.size(); ++i) {
    const Detection& d = with_tiles[i];
    if (i > 0) {
      EXPECT_LE(d.score, with_tiles[i - 1].score);
    }
    EXPECT_GE(d.score, config.score_threshold);
    EXPECT_GE(d.box.x_min, 0.f);
    EXPECT_LE(d.box.x_max, static_cast<float>(frame.color.width));
    EXPECT_GE(d.box.y_min, 0.f);
    EXPECT_LE(d.box.y_max, static_cast<float>(frame.color.height));
  }
}

}  // namespace
}  // namespace objmap
