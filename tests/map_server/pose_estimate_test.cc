// A MapServer with pose_source estimate, fed real redkitchen keyframes without poses: it tracks
// them, refuses what it cannot track, resumes after a restart, and moves the mapped keyframes
// when a loop closes.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "dataset/sequence_reader.h"
#include "evaluation/trajectory_evaluation.h"
#include "map_server/map_server.h"
#include "test_data.h"

namespace objmap {
namespace {

class PoseEstimate : public ::testing::Test {
 protected:
  PoseEstimate() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    db_path_ = ::testing::TempDir() + "objmap_pose_estimate_" + std::to_string(getpid()) + "_" +
               info->name() + ".db";
    RemoveDatabase();
    config_.pose_source = PoseSource::kEstimate;
  }
  ~PoseEstimate() override { RemoveDatabase(); }

  void RemoveDatabase() const {
    for (const char* suffix : {"", "-wal", "-shm"}) std::remove((db_path_ + suffix).c_str());
  }

  std::unique_ptr<MapServer> OpenServer() const {
    std::string why;
    auto server = MapServer::Open(config_, db_path_, nullptr, &why);
    EXPECT_TRUE(server) << why;
    return server;
  }

  // Sequence frame `index` as a client without poses sends it: the pose field holds nonsense
  // the server must ignore.
  RgbdFrame Keyframe(std::size_t index) const {
    RgbdFrame frame;
    std::string why;
    EXPECT_TRUE(reader_->ReadFrame(index, &frame, &why)) << why;
    frame.T_W_C = Eigen::Isometry3d::Identity();
    frame.T_W_C.translation() = Eigen::Vector3d(50.0, -20.0, 3.0);
    return frame;
  }
  Eigen::Isometry3d Reference(std::size_t index) const {
    RgbdFrame frame;
    std::string why;
    EXPECT_TRUE(reader_->ReadFrame(index, &frame, &why)) << why;
    return frame.T_W_C;
  }

  bool OpenSequenceOrSkip() {
    const std::string folder = testing::SharedDataPath("redkitchen");
    if (!testing::Exists(folder)) return false;
    std::string why;
    reader_ = OpenSequence(folder, &why);
    EXPECT_NE(reader_, nullptr) << why;
    return reader_ != nullptr;
  }

  static void WaitUntilIdle(const MapServer& server) {
    for (int i = 0; i < 600; ++i) {
      const ServerStatus status = server.Status();
      if (status.queue_length == 0 && !status.regenerating) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << "the server is still busy after 60 s";
  }

  MapServerConfig config_;
  std::string db_path_;
  std::unique_ptr<SequenceReader> reader_;
};

// With server.estimate_from_first_pose an empty map starts at the pose its first keyframe
// carries (a dataset whose poses only score the estimate: the map shares their frame); the poses
// of later keyframes are still ignored, and each is tracked near the dataset's own.
TEST_F(PoseEstimate, AnEmptyMapCanStartAtTheFirstKeyframesPose) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "../shared/data/redkitchen is absent";
  config_.estimate_from_first_pose = true;
  auto server = OpenServer();
  ASSERT_TRUE(server);
  RgbdFrame first = Keyframe(0);
  first.T_W_C = Reference(0);
  AddKeyframeOutcome outcome;
  ASSERT_TRUE(server->AddKeyframe(first, std::vector<Detection>{}, &outcome).ok());
  EXPECT_TRUE(outcome.T_W_C.isApprox(Reference(0), 1e-9));
  for (std::size_t index = 3; index <= 30; index += 3) {
    ASSERT_TRUE(server->AddKeyframe(Keyframe(index), std::vector<Detection>{}, &outcome).ok())
        << "frame " << index;  // its pose field holds nonsense, ignored
    const Eigen::Isometry3d error = Reference(index).inverse() * outcome.T_W_C;
    EXPECT_LT(error.translation().norm(), 0.05) << "frame " << index;
  }
  // A first pose that is not a rigid transform is refused.
  server.reset();
  RemoveDatabase();
  server = OpenServer();
  ASSERT_TRUE(server);
  RgbdFrame broken = Keyframe(0);
  broken.T_W_C.matrix()(0, 0) = 2.0;
  const ServiceStatus refused = server->AddKeyframe(broken, std::vector<Detection>{}, &outcome);
  EXPECT_EQ(refused.code, StatusCode::kInvalidArgument) << refused.message;
  EXPECT_EQ(server->Status().keyframes, 0u);
}

TEST_F(PoseEstimate, KeyframesWithoutPosesAreTrackedBlankOnesRefusedAndARestartResumes) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "../shared/data/redkitchen is absent";
  std::vector<TrajectoryPose> estimated, reference;
  {
    auto server = OpenServer();
    ASSERT_TRUE(server);
    ASSERT_TRUE(server->estimates_poses());
    for (std::size_t index = 0; index <= 60; index += 3) {
      AddKeyframeOutcome outcome;
      const ServiceStatus status = server->AddKeyframe(Keyframe(index), std::vector<Detection>{}, &outcome);
      ASSERT_TRUE(status.ok()) << "frame " << index << ": " << status.message;
      estimated.push_back({index / 30.0, outcome.T_W_C});
      reference.push_back({index / 30.0, Reference(index)});
    }
    // A blank frame cannot be tracked: refused with the reason, and nothing is mapped.
    RgbdFrame blank = Keyframe(61);
    std::fill(blank.color.rgb.begin(), blank.color.rgb.end(), std::uint8_t{128});
    std::fill(blank.depth.depth_m.begin(), blank.depth.depth_m.end(), 1.5f);
    const std::size_t keyframes_before = server->Status().keyframes;
    AddKeyframeOutcome refused;
    const ServiceStatus lost = server->AddKeyframe(blank, std::vector<Detection>{}, &refused);
    EXPECT_EQ(lost.code, StatusCode::kFailedPrecondition);
    EXPECT_NE(lost.message.find("tracking lost"), std::string::npos) << lost.message;
    EXPECT_EQ(server->Status().keyframes, keyframes_before);
  }
  // The world frame is the first keyframe's camera: compare after alignment.
  TrajectoryErrors errors;
  std::string why;
  ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
  std::printf("21 keyframes, 4.5 cm apart: ATE RMSE %.4f m\n", errors.ate_rmse_m);
  EXPECT_LT(errors.ate_rmse_m, 0.02);
  EXPECT_TRUE(estimated.front().T_W_C.isApprox(Eigen::Isometry3d::Identity()));

  // A restart: tracking resumes from the newest stored keyframe, in the same world frame.
  auto server = OpenServer();
  ASSERT_TRUE(server);
  AddKeyframeOutcome outcome;
  const ServiceStatus status = server->AddKeyframe(Keyframe(63), std::vector<Detection>{}, &outcome);
  ASSERT_TRUE(status.ok()) << status.message;
  const Eigen::Isometry3d expected = Reference(0).inverse() * Reference(63);
  const Eigen::Isometry3d error = expected.inverse() * outcome.T_W_C;
  EXPECT_LT(error.translation().norm(), 0.05) << outcome.T_W_C.matrix();
}

TEST_F(PoseEstimate, ALoopTheOdometryClosesMovesTheMappedKeyframes) {
  if (!OpenSequenceOrSkip()) GTEST_SKIP() << "../shared/data/redkitchen is absent";
  auto server = OpenServer();
  ASSERT_TRUE(server);
  // Out along frames 0..180 and back (the camera retraces its path): the way back passes
  // keyframes made long before.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i <= 180; i += 9) order.push_back(i);
  for (int i = 175; i > 0; i -= 9) order.push_back(static_cast<std::size_t>(i));
  std::vector<TrajectoryPose> as_mapped, reference;
  int loops = 0;
  for (std::size_t n = 0; n < order.size(); ++n) {
    AddKeyframeOutcome outcome;
    const ServiceStatus status = server->AddKeyframe(Keyframe(order[n]), std::vector<Detection>{}, &outcome);
    ASSERT_TRUE(status.ok()) << "frame " << order[n] << ": " << status.message;
    loops += outcome.loops_closed;
    as_mapped.push_back({n / 30.0, outcome.T_W_C});
    reference.push_back({n / 30.0, Reference(order[n])});
  }
  ASSERT_GE(loops, 1) << "no loop closed on the way back";
  WaitUntilIdle(*server);
  // The stored poses are the loop-corrected ones, not those the keyframes were mapped at.
  std::vector<KeyframeSummary> stored;
  std::uint64_t version = 0;
  ASSERT_TRUE(server->ListKeyframes(0, 0, &stored, &version).ok());
  ASSERT_EQ(stored.size(), order.size());
  std::vector<TrajectoryPose> corrected = as_mapped;
  int moved = 0;
  for (std::size_t n = 0; n < stored.size(); ++n) {
    corrected[n].T_W_C = stored[n].T_W_C;
    if (!stored[n].T_W_C.isApprox(as_mapped[n].T_W_C, 1e-9)) ++moved;
  }
  EXPECT_GT(moved, 0);
  TrajectoryErrors mapped_errors, corrected_errors;
  std::string why;
  ASSERT_TRUE(EvaluateTrajectory(as_mapped, reference, {}, &mapped_errors, &why)) << why;
  ASSERT_TRUE(EvaluateTrajectory(corrected, reference, {}, &corrected_errors, &why)) << why;
  std::printf("%d loops, %d keyframes moved: ATE as mapped %.4f m, stored after the loops %.4f m\n",
              loops, moved, mapped_errors.ate_rmse_m, corrected_errors.ate_rmse_m);
  EXPECT_LE(corrected_errors.ate_rmse_m, mapped_errors.ate_rmse_m);
  EXPECT_LT(corrected_errors.ate_rmse_m, 0.03);
}

TEST(PoseSourceNames, ParseAndNameEachOther) {
  for (const PoseSource source : {PoseSource::kRequest, PoseSource::kEstimate}) {
    PoseSource parsed = source == PoseSource::kRequest ? PoseSource::kEstimate : PoseSource::kRequest;
    ASSERT_TRUE(ParsePoseSource(PoseSourceName(source), &parsed));
    EXPECT_EQ(parsed, source);
  }
  PoseSource unchanged = PoseSource::kRequest;
  EXPECT_FALSE(ParsePoseSource("gps", &unchanged));
  EXPECT_EQ(unchanged, PoseSource::kRequest);
}

}  // namespace
}  // namespace objmap
