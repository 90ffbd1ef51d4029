// `objmap map` on a bag made by objmap_dataset_player from redkitchen maps like `objmap map` on
// the same frames as a folder; bad bags fail with messages a user can act on.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "dataset/sequence_reader.h"
#include "dataset/trajectory.h"
#include "evaluation/trajectory_evaluation.h"
#include "run_objmap.h"
#include "test_bags.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::RunCommand;
using testing::RunObjmap;

// Every 10th frame of 0..599: 60 frames, 32 keyframes with the default selector (10 cm / 10
// degrees), enough for objects to reach the inventory's 3 observations.
constexpr int kStride = 10;
constexpr int kFrames = 60;

class RosbagMap : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_rosbag_map_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file);
}

std::string InventoryText(const nlohmann::json& objects) {
  std::string text;
  for (const auto& entry : objects["inventory"]) {
    text +=
        entry["class"].get<std::string>() + " " + std::to_string(entry["count"].get<int>()) + "; ";
  }
  return text;
}

// The largest distance from an inventory object of `a` to the nearest one of its class in `b`.
double WorstCentroidGap(const nlohmann::json& a, const nlohmann::json& b) {
  double worst = 0.0;
  for (const auto& object : a["objects"]) {
    if (!object["in_inventory"].get<bool>()) continue;
    double nearest = 1e9;
    for (const auto& other : b["objects"]) {
      if (!other["in_inventory"].get<bool>() || other["class"] != object["class"]) continue;
      double squared = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double d = object["centroid"][k].get<double>() - other["centroid"][k].get<double>();
        squared += d * d;
      }
      nearest = std::min(nearest, std::sqrt(squared));
    }
    worst = std::max(worst, nearest);
  }
  return worst;
}

TEST_F(RosbagMap, PlayerBagMapsLikeTheFolder) {
  const std::string kitchen = objmap::testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(kitchen + "/frame-000590.pose.txt");
  OBJMAP_REQUIRE_PATH(std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb");
  // The folder run reads the same frames through links named as a 7-Scenes folder.
  fs::create_directories(Path("every10"));
  fs::create_symlink(kitchen + "/camera-intrinsics.txt", Path("every10/camera-intrinsics.txt"));
  for (int k = 0; k < kFrames; ++k) {
    char source[32], link[32];
    std::snprintf(source, sizeof(source), "frame-%06d", k * kStride);
    std::snprintf(link, sizeof(link), "frame-%06d", k);
    for (const char* suffix : {".color.jpg", ".depth.png", ".pose.txt"}) {
      fs::create_symlink(kitchen + "/" + source + suffix, Path("every10/") + link + suffix);
    }
  }
  const CommandResult play =
      RunCommand(std::string(OBJMAP_PLAYER_PATH) + " " + kitchen + " --write-bag " +
                 Path("kitchen.bag") + " --every-nth-frame " + std::to_string(kStride) +
                 " --max-frames " + std::to_string(kFrames * kStride));
  ASSERT_EQ(play.exit_code, 0) << play.output;
  EXPECT_NE(play.output.find("played 60 frames"), std::string::npos) << play.output;

  const CommandResult from_bag = RunObjmap("map " + Path("kitchen.bag") + " --out " + Path("A"));
  ASSERT_EQ(from_bag.exit_code, 0) << from_bag.output;
  EXPECT_NE(from_bag.output.find("rosbag " + Path("kitchen.bag") + ": 60 frames"),
            std::string::npos)
      << from_bag.output;
  const CommandResult from_folder = RunObjmap("map " + Path("every10") + " --out " + Path("B"));
  ASSERT_EQ(from_folder.exit_code, 0) << from_folder.output;

  const nlohmann::json a = ReadJson(Path("A/objects.json"));
  const nlohmann::json b = ReadJson(Path("B/objects.json"));
  std::cout << "bag:    " << a["keyframes"] << " keyframes, inventory " << InventoryText(a) << "\n"
            << "folder: " << b["keyframes"] << " keyframes, inventory " << InventoryText(b) << "\n";
  ASSERT_FALSE(b["inventory"].empty()) << "the folder run confirmed no object";
  EXPECT_EQ(a["keyframes"], b["keyframes"]);
  EXPECT_EQ(InventoryText(a), InventoryText(b));
  const double gap_m = std::max(WorstCentroidGap(a, b), WorstCentroidGap(b, a));
  std::cout << "largest centroid gap between the two inventories: " << gap_m * 1000.0 << " mm\n";
  EXPECT_LE(gap_m, 0.005);
}

TEST_F(RosbagMap, BadBagsFailWithTheReason) {
  CommandResult run = RunObjmap("map " + Path("absent.bag") + " --out " + Path("out"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("objmap map: " + Path("absent.bag") + ": no such file"),
            std::string::npos)
      << run.output;

  std::ofstream(Path("notes.bag")) << "not a bag\n";
  run = RunObjmap("map " + Path("notes.bag") + " --out " + Path("out"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find(Path("notes.bag") + ": not a ROS bag"), std::string::npos)
      << run.output;

  RgbdFrame frame;
  frame.intrinsics.width = frame.color.width = frame.depth.width = 8;
  frame.intrinsics.height = frame.color.height = frame.depth.height = 6;
  frame.color.rgb.assign(8 * 6 * 3, 100);
  frame.depth.depth_m.assign(8 * 6, 1.0f);
  objmap::testing::WriteTestBag(Path("small.bag"), {frame, frame});
  run = RunObjmap("map " + Path("small.bag") + " --out " + Path("out") +
                  " --bag-depth-topic /camera/depth/image");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("depth image topic '/camera/depth/image' is not in " +
                            Path("small.bag") + "; its topics: /depth/image"),
            std::string::npos)
      << run.output;
}

TEST_F(RosbagMap, FrameWithoutTfIsSkippedWithTheTransformNamed) {
  RgbdFrame frame;
  frame.intrinsics.width = frame.color.width = frame.depth.width = 64;
  frame.intrinsics.height = frame.color.height = frame.depth.height = 48;
  frame.intrinsics.cx = 32;
  frame.intrinsics.cy = 24;
  frame.color.rgb.assign(64 * 48 * 3, 100);
  frame.depth.depth_m.assign(64 * 48, 1.0f);
  objmap::testing::TestBagOptions options;
  options.frames_with_tf = 2;
  objmap::testing::WriteTestBag(Path("gap.bag"), {frame, frame, frame}, options);
  std::ofstream(Path("detections.json")) << R"({"frames": {}})";
  const CommandResult run = RunObjmap("map " + Path("gap.bag") + " --out " + Path("out") +
                                      " --detections " + Path("detections.json"));
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("skipped frame 2: " + Path("gap.bag") +
                            " frame 2 (t=100.200000000): no transform from 'camera' to 'map' "
                            "(/tf, /tf_static) at t=100.200000000"),
            std::string::npos)
      << run.output;
}

// A bag with images and camera info but no /tf: `objmap map` (--poses auto) tracks the camera
// instead of refusing the bag, writes the trajectory and maps with it; `--poses input` still
// refuses it, naming what is missing.
TEST_F(RosbagMap, ABagWithoutTfIsMappedWithEstimatedPoses) {
  const std::string kitchen = objmap::testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(kitchen);
  std::string why;
  const auto reader = OpenSequence(kitchen, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<RgbdFrame> frames;
  std::vector<TrajectoryPose> reference;
  for (std::size_t i = 0; i < 60; i += 3) {
    RgbdFrame frame;
    ASSERT_TRUE(reader->ReadFrame(i, &frame, &why)) << why;
    reference.push_back({0.0, frame.T_W_C});
    frames.push_back(std::move(frame));
  }
  objmap::testing::TestBagOptions options;
  options.write_tf = false;
  objmap::testing::WriteTestBag(Path("no_tf.bag"), frames, options);
  std::ofstream(Path("detections.json")) << R"({"frames": {}})";

  const CommandResult refused = RunObjmap("map " + Path("no_tf.bag") + " --out " + Path("in") +
                                          " --detections " + Path("detections.json") +
                                          " --poses input");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.output.find("has no /tf or /tf_static messages for the camera poses"),
            std::string::npos)
      << refused.output;

  const CommandResult run = RunObjmap("map " + Path("no_tf.bag") + " --out " + Path("out") +
                                      " --detections " + Path("detections.json"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("the bag has no /tf or /tf_static messages; poses estimated by RGB-D "
                            "odometry"),
            std::string::npos)
      << run.output;
  std::vector<TrajectoryPose> estimated;
  ASSERT_TRUE(ReadTumTrajectory(Path("out/trajectory.txt"), &estimated, &why)) << why;
  ASSERT_EQ(estimated.size(), reference.size()) << run.output;
  for (std::size_t i = 0; i < estimated.size(); ++i) reference[i].stamp_s = estimated[i].stamp_s;
  TrajectoryErrors errors;
  ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
  EXPECT_LT(errors.ate_rmse_m, 0.02);
  EXPECT_TRUE(fs::exists(Path("out/map.bt")));
}

}  // namespace
}  // namespace objmap
