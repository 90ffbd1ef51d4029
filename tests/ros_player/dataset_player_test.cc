// objmap_dataset_player against a real rosmaster and objmap_node: with ~wait_for_node every
// frame played is handled by the node, even at a rate the node cannot keep; bad parameters and
// options are refused by name.
#include <gtest/gtest.h>
#include <objmap_msgs/Status.h>
#include <ros/ros.h>

#include <filesystem>

#include "ros_processes.h"
#include "run_objmap.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::RosMaster;

class DatasetPlayer : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_player_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs the player as a ROS node with private parameters `params` ("_rate:=5"); its exit code.
  int Play(const std::string& name, std::vector<std::string> params, std::string* log) {
    std::vector<std::string> argv = {OBJMAP_PLAYER_PATH, "__name:=" + name};
    argv.insert(argv.end(), params.begin(), params.end());
    ChildProcess player(argv, Path(name + ".log"));
    std::string why;
    if (!player.Start(&why)) return -1;
    const int code = player.WaitForExit(std::chrono::seconds(300));
    *log = player.Log();
    return code;
  }

  fs::path dir_;
};

TEST_F(DatasetPlayer, WaitsForTheNodeSoThatNoFrameIsDropped) {
  const std::string kitchen = objmap::testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(kitchen + "/frame-000190.pose.txt");
  RosMaster master(dir_.string());
  std::string why;
  ASSERT_TRUE(master.Start(&why)) << why;
  // Structure only (no detector): the test is about the hand-over, not the objects.
  ChildProcess node({OBJMAP_NODE_PATH, "_database:=" + Path("node.db"), "_run_detector:=false",
                     "_sync_max_interval_s:=0.0"},
                    Path("node.log"));
  ASSERT_TRUE(node.Start(&why)) << why;
  std::string log;
  // 100 Hz is faster than the node maps a keyframe: without the wait, frames would be dropped.
  const int code = Play("player",
                        {"_dataset:=" + kitchen, "_max_frames:=200", "_every_nth_frame:=10",
                         "_rate:=100.0", "_wait_for_node:=/objmap_node/status"},
                        &log);
  ASSERT_EQ(code, 0) << log << "\nnode:\n" << node.Log();
  EXPECT_NE(log.find("played 20 frames"), std::string::npos) << log;

  int argc = 0;
  ros::init(argc, nullptr, "objmap_player_test",
            ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
  objmap_msgs::Status status;
  ASSERT_TRUE(ros::service::call("/objmap_node/status", status)) << node.Log();
  EXPECT_EQ(status.response.frames_received, 20) << node.Log();
  EXPECT_EQ(status.response.frames_rejected, 0) << status.response.last_rejection;
  EXPECT_GE(status.response.keyframes_sent, 5);
  std::cout << "objmap_node: " << status.response.frames_received << " frames received, "
            << status.response.keyframes_sent << " keyframes\n";

  // Mistyped and unknown parameters name themselves.
  EXPECT_EQ(Play("typo", {"_dataset:=" + kitchen, "_rate:=fast"}, &log), 2);
  EXPECT_NE(log.find("~rate: expected a number, got 'fast'"), std::string::npos) << log;
  EXPECT_EQ(Play("unknown", {"_dataset:=" + kitchen, "_frame_rate:=5"}, &log), 2);
  EXPECT_NE(log.find("~frame_rate: unknown parameter"), std::string::npos) << log;
  ros::shutdown();
  node.Stop(SIGINT);
}

TEST_F(DatasetPlayer, CommandLineFormRefusesUnknownOptionsWithoutAMaster) {
  const objmap::testing::CommandResult run =
      objmap::testing::RunCommand(std::string(OBJMAP_PLAYER_PATH) + " " + Path("") +
                                  " --write-bag " + Path("x.bag") + " --frame-rate 5");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--frame-rate: unknown option"), std::string::npos) << run.output;
  const objmap::testing::CommandResult empty = objmap::testing::RunCommand(
      std::string(OBJMAP_PLAYER_PATH) + " " + Path("") + " --write-bag " + Path("x.bag"));
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_NE(empty.output.find("no frame-NNNNNN.depth.png files"), std::string::npos)
      << empty.output;
}

}  // namespace
}  // namespace objmap
