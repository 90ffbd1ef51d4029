// RgbdOdometry on real redkitchen frames (error against the sequence's poses), on a view of a
// real frame rendered from a known second pose, and on blank frames (lost, said, recovered).

#include "odometry/rgbd_odometry.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "dataset/sequence_reader.h"
#include "evaluation/trajectory_evaluation.h"
#include "odometry/odometry_stream.h"
#include "test_data.h"

namespace objmap {
namespace {

constexpr double kDegPerRad = 57.29577951308232;

double AngleDeg(const Eigen::Isometry3d& T) { return Eigen::AngleAxisd(T.linear()).angle() * kDegPerRad; }

RgbdFrame ReadFrame(const SequenceReader& reader, std::size_t index) {
  RgbdFrame frame;
  std::string why;
  EXPECT_TRUE(reader.ReadFrame(index, &frame, &why)) << why;
  return frame;
}

// `frame` seen from a camera moved by T_C0_C1 (forward-warped colour and depth, nearest point
// per pixel): what the camera would see there, up to disocclusions, which stay empty.
RgbdFrame RenderMoved(const RgbdFrame& frame, const Eigen::Isometry3d& T_C0_C1) {
  const CameraIntrinsics& K = frame.intrinsics;
  RgbdFrame moved = frame;
  moved.depth.depth_m.assign(frame.depth.depth_m.size(), 0.f);
  moved.color.rgb.assign(frame.color.rgb.size(), 0);
  const Eigen::Isometry3d T_C1_C0 = T_C0_C1.inverse();
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * K.width + u;
      const double z = frame.depth.depth_m[i];
      if (!(z > 0.0)) continue;
      const Eigen::Vector3d p0((u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z);
      const Eigen::Vector3d p1 = T_C1_C0 * p0;
      if (p1.z() <= 0.0) continue;
      // Splatted over the 2 x 2 pixels around the projection, so that the image has no cracks
      // where the surface stretches.
      const double x = K.fx * p1.x() / p1.z() + K.cx, y = K.fy * p1.y() / p1.z() + K.cy;
      for (int v1 = static_cast<int>(std::floor(y)); v1 <= static_cast<int>(std::floor(y)) + 1;
           ++v1) {
        for (int u1 = static_cast<int>(std::floor(x)); u1 <= static_cast<int>(std::floor(x)) + 1;
             ++u1) {
          if (u1 < 0 || v1 < 0 || u1 >= K.width || v1 >= K.height) continue;
          const std::size_t j = static_cast<std::size_t>(v1) * K.width + u1;
          float& depth = moved.depth.depth_m[j];
          if (depth > 0.f && depth <= p1.z()) continue;
          depth = static_cast<float>(p1.z());
          for (int c = 0; c < 3; ++c) moved.color.rgb[3 * j + c] = frame.color.rgb[3 * i + c];
        }
      }
    }
  }
  return moved;
}

TEST(RgbdOdometry, ARenderedSecondViewGivesItsKnownPose) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  // 7-Scenes colour is not registered to depth, so warping it by depth smears object edges,
  // where most corners are: a small motion keeps enough of them.
  for (std::size_t index : {0u, 300u}) {
    const RgbdFrame first = ReadFrame(*reader, index);
    Eigen::Isometry3d T_C0_C1 = Eigen::Isometry3d::Identity();
    T_C0_C1.translate(Eigen::Vector3d(0.02, -0.01, 0.015));
    T_C0_C1.rotate(Eigen::AngleAxisd(0.025, Eigen::Vector3d(0.3, 1.0, 0.1).normalized()));
    RgbdOdometry odometry{OdometryConfig{}};
    ASSERT_EQ(odometry.Track(first).status, TrackingStatus::kInitialized);
    const TrackingReport report = odometry.Track(RenderMoved(first, T_C0_C1));
    ASSERT_EQ(report.status, TrackingStatus::kTracked) << "frame " << index << ": " << report.why;
    const Eigen::Isometry3d error = T_C0_C1.inverse() * report.T_W_C;
    // A wrong frame convention would be off by twice the motion (5 cm, 3 degrees).
    EXPECT_LT(error.translation().norm(), 0.008) << "frame " << index;
    EXPECT_LT(AngleDeg(error), 0.5) << "frame " << index;
    EXPECT_GE(report.inliers, 50) << "frame " << index;
  }
}

TEST(RgbdOdometry, RealFramesStayNearTheSequencePoses) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  // Two stretches of 120 frames (4 s): the start, and one turning past the table. The bounds
  // hold what frame-to-keyframe tracking gives there (measured 2026-12-05 with the dense depth
  // step: 0.8 and 2.0 cm; 0.6 and 5.6 cm without it);
  // drift over longer stretches is for loop closure to remove.
  for (const auto& [first, bound_m] : {std::pair<std::size_t, double>{0, 0.02}, {400, 0.04}}) {
    RgbdOdometry odometry{OdometryConfig{}};
    std::vector<TrajectoryPose> estimated, reference;
    for (std::size_t i = first; i < first + 120; ++i) {
      const RgbdFrame frame = ReadFrame(*reader, i);
      const TrackingReport report = odometry.Track(frame);
      ASSERT_NE(report.status, TrackingStatus::kLost) << "frame " << i << ": " << report.why;
      estimated.push_back({i / 30.0, report.T_W_C});
      reference.push_back({i / 30.0, frame.T_W_C});
    }
    TrajectoryErrors errors;
    ASSERT_TRUE(EvaluateTrajectory(estimated, reference, {}, &errors, &why)) << why;
    EXPECT_LT(errors.ate_rmse_m, bound_m) << "frames " << first << "..";
    std::printf("frames %zu..%zu: ATE RMSE %.4f m\n", first, first + 119, errors.ate_rmse_m);
    EXPECT_GT(odometry.num_keyframes(), 1);
  }
}

TEST(RgbdOdometry, BlankFramesAreLostWithTheReasonAndTrackingRecovers) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  RgbdOdometry odometry{OdometryConfig{}};
  for (std::size_t i = 0; i < 10; ++i) {
    ASSERT_NE(odometry.Track(ReadFrame(*reader, i)).status, TrackingStatus::kLost);
  }
  // A blank wall: one grey, flat depth. Then a dark frame: the same image at 2 % brightness.
  RgbdFrame blank = ReadFrame(*reader, 10);
  std::fill(blank.color.rgb.begin(), blank.color.rgb.end(), std::uint8_t{128});
  std::fill(blank.depth.depth_m.begin(), blank.depth.depth_m.end(), 1.5f);
  RgbdFrame dark = ReadFrame(*reader, 11);
  for (std::uint8_t& value : dark.color.rgb) value = static_cast<std::uint8_t>(value / 50);
  for (const RgbdFrame* frame : {&blank, &dark}) {
    const TrackingReport report = odometry.Track(*frame);
    EXPECT_EQ(report.status, TrackingStatus::kLost);
    EXPECT_FALSE(report.why.empty());
  }
  // A frame whose image does not fit its intrinsics is lost too, with the reason.
  RgbdFrame wrong = ReadFrame(*reader, 12);
  wrong.intrinsics.width = 320;
  const TrackingReport refused = odometry.Track(wrong);
  EXPECT_EQ(refused.status, TrackingStatus::kLost);
  EXPECT_NE(refused.why.find("sizes differ"), std::string::npos) << refused.why;
  // The camera is back: tracking resumes near the sequence's pose (the world frame is the
  // first camera's, so compare motions from frame 0).
  const RgbdFrame origin = ReadFrame(*reader, 0);
  const RgbdFrame back = ReadFrame(*reader, 14);
  const TrackingReport report = odometry.Track(back);
  ASSERT_NE(report.status, TrackingStatus::kLost) << report.why;
  const Eigen::Isometry3d expected = origin.T_W_C.inverse() * back.T_W_C;
  EXPECT_LT((expected.inverse() * report.T_W_C).translation().norm(), 0.03);
}

// A saved map of frames 250..350 (every 5th, at the sequence's poses), then a session of the
// frames `session` (in that order) on it; the sequence's pose of every keyframe the session made.
struct SessionOnMap {
  std::unique_ptr<RgbdOdometry> odometry;
  int map_keyframes = 0;
  std::vector<TrackingReport> reports;
  std::vector<Eigen::Isometry3d> keyframe_truth;  // per session keyframe, in order
};

SessionOnMap TrackSessionOnMap(const SequenceReader& reader,
                               const std::vector<std::size_t>& session) {
  SessionOnMap run;
  run.odometry = std::make_unique<RgbdOdometry>(OdometryConfig{});
  for (std::size_t i = 250; i <= 350; i += 5) {
    std::string why;
    EXPECT_TRUE(run.odometry->AddMapKeyframe(ReadFrame(reader, i), &why)) << why;
  }
  run.map_keyframes = run.odometry->num_keyframes();
  for (const std::size_t i : session) {
    const RgbdFrame frame = ReadFrame(reader, i);
    run.reports.push_back(run.odometry->Track(frame));
    if (run.reports.back().new_keyframe) run.keyframe_truth.push_back(frame.T_W_C);
  }
  return run;
}

// A session starting where the map has no view like its own (frame 640; the map holds frames
// 250..350) is tracked in a provisional fragment; the first frame a map keyframe places attaches
// it, and every keyframe the session made, before and after, lies near the sequence's pose.
TEST(RgbdOdometry, ASessionStartingOffTheMapIsTrackedApartThenAttached) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<std::size_t> session;
  for (std::size_t i = 640; i >= 540; i -= 5) session.push_back(i);  // walking back into the map
  const SessionOnMap run = TrackSessionOnMap(*reader, session);
  ASSERT_EQ(run.reports.front().status, TrackingStatus::kProvisional) << run.reports.front().why;
  EXPECT_EQ(run.reports.front().fragment, 1);
  std::size_t attached_at = run.reports.size();
  for (std::size_t i = 0; i < run.reports.size(); ++i) {
    const TrackingReport& report = run.reports[i];
    ASSERT_NE(report.status, TrackingStatus::kLost) << "frame " << session[i] << ": " << report.why;
    if (report.attached_fragment == 1) attached_at = i;
    if (attached_at == run.reports.size()) {
      EXPECT_EQ(report.fragment, 1) << "frame " << session[i];
    } else {
      EXPECT_EQ(report.fragment, 0) << "frame " << session[i];
    }
  }
  ASSERT_LT(attached_at, run.reports.size()) << "the session was never placed in the map";
  EXPECT_GT(attached_at, 0u);
  EXPECT_EQ(run.odometry->fragments_started(), 1);
  EXPECT_EQ(run.odometry->fragments_attached(), 1);
  // Every keyframe of the session, those made while provisional included, in the map's frame
  // near the sequence's pose (whose two halves disagree by about 2 degrees, docs/evaluation.md).
  ASSERT_EQ(static_cast<std::size_t>(run.odometry->num_keyframes() - run.map_keyframes),
            run.keyframe_truth.size());
  for (int k = run.map_keyframes; k < run.odometry->num_keyframes(); ++k) {
    EXPECT_EQ(run.odometry->KeyframeFragment(k), 0) << "keyframe " << k;
    const Eigen::Isometry3d error =
        run.keyframe_truth[static_cast<std::size_t>(k - run.map_keyframes)].inverse() *
        run.odometry->KeyframePose(k);
    EXPECT_LT(error.translation().norm(), 0.05) << "keyframe " << k;
    EXPECT_LT(AngleDeg(error), 3.0) << "keyframe " << k;
  }
}

// A session in a part of the kitchen the map does not hold (frames 750..800 against a map of
// 250..350) is never placed: it stays a provisional fragment of its own, and with the option off
// its frames are lost as before.
TEST(RgbdOdometry, ASessionTheMapDoesNotHoldStaysApart) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<std::size_t> session;
  for (std::size_t i = 750; i <= 800; i += 5) session.push_back(i);
  const SessionOnMap run = TrackSessionOnMap(*reader, session);
  for (std::size_t i = 0; i < run.reports.size(); ++i) {
    EXPECT_EQ(run.reports[i].status, TrackingStatus::kProvisional) << "frame " << session[i];
    EXPECT_GT(run.reports[i].fragment, 0) << "frame " << session[i];
    EXPECT_EQ(run.reports[i].attached_fragment, -1) << "frame " << session[i];
  }
  EXPECT_EQ(run.odometry->fragments_attached(), 0);
  for (int k = run.map_keyframes; k < run.odometry->num_keyframes(); ++k) {
    EXPECT_NE(run.odometry->KeyframeFragment(k), 0) << "keyframe " << k;
  }

  OdometryConfig without;
  without.provisional_fragments = false;
  RgbdOdometry odometry{without};
  for (std::size_t i = 250; i <= 350; i += 5) {
    ASSERT_TRUE(odometry.AddMapKeyframe(ReadFrame(*reader, i), &why)) << why;
  }
  const TrackingReport lost = odometry.Track(ReadFrame(*reader, 750));
  EXPECT_EQ(lost.status, TrackingStatus::kLost);
  EXPECT_FALSE(lost.why.empty());
}

// A loop for certain: frames 0..239 forward, then back to 0 (the camera retraces its path), so
// the way back passes keyframes made long before. Loop closure must find them and pull the drift
// of the way out in (measured 2026-12-05: 31 loops, ATE 1.67 cm as tracked, 1.42 cm on the
// keyframes' final poses; with the loops closed in the background 1.63 and 1.42 cm).
void TrackOutAndBack(bool background) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < 240; i += 2) order.push_back(i);
  for (std::size_t i = 240; i-- > 0;) {
    if (i % 2 == 1) order.push_back(i);
  }
  OdometryConfig config;
  config.background_loop_closure = background;
  RgbdOdometry odometry{config};
  std::vector<TrajectoryPose> as_tracked, reference;
  std::vector<std::pair<int, Eigen::Isometry3d>> on_keyframe;  // reference keyframe, T_K_C
  int reported_loops = 0;
  for (std::size_t n = 0; n < order.size(); ++n) {
    const RgbdFrame frame = ReadFrame(*reader, order[n]);
    const TrackingReport report = odometry.Track(frame);
    ASSERT_NE(report.status, TrackingStatus::kLost) << "frame " << order[n] << ": " << report.why;
    reported_loops += report.loops_closed;
    as_tracked.push_back({n / 30.0, report.T_W_C});
    reference.push_back({n / 30.0, frame.T_W_C});
    on_keyframe.emplace_back(report.reference_keyframe,
                             odometry.KeyframePose(report.reference_keyframe).inverse() * report.T_W_C);
  }
  // Searches still under way when the frames end (background only) are waited for.
  reported_loops += odometry.FinishLoopClosure();
  EXPECT_EQ(reported_loops, odometry.loops_closed());
  std::vector<TrajectoryPose> after = as_tracked;
  for (std::size_t n = 0; n < after.size(); ++n) {
    after[n].T_W_C = odometry.KeyframePose(on_keyframe[n].first) * on_keyframe[n].second;
  }
  EXPECT_GE(odometry.loops_closed(), 1);
  TrajectoryErrors tracked_errors, after_errors;
  ASSERT_TRUE(EvaluateTrajectory(as_tracked, reference, {}, &tracked_errors, &why)) << why;
  ASSERT_TRUE(EvaluateTrajectory(after, reference, {}, &after_errors, &why)) << why;
  std::printf("%s: %d loops; ATE as tracked %.4f m, on the final keyframe poses %.4f m\n",
              background ? "background" : "in Track", odometry.loops_closed(),
              tracked_errors.ate_rmse_m, after_errors.ate_rmse_m);
  EXPECT_LT(after_errors.ate_rmse_m, tracked_errors.ate_rmse_m);
  EXPECT_LT(after_errors.ate_rmse_m, 0.03);
}

TEST(RgbdOdometry, ALoopBackToTheStartPullsTheTrajectoryIn) { TrackOutAndBack(false); }

TEST(RgbdOdometry, LoopsClosedInTheBackgroundPullTheTrajectoryInToo) { TrackOutAndBack(true); }

TEST(RgbdOdometry, AnOdometryStoppedWhileItsLoopSearchRunsLeavesCleanly) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  OdometryConfig config;
  config.background_loop_closure = true;
  config.loop_min_keyframe_gap = 1;  // every keyframe has candidates: the worker is busy
  config.keyframe_distance_m = 0.02;
  int keyframes = 0;
  {
    RgbdOdometry odometry{config};
    for (std::size_t i = 0; i < 60; i += 2) {
      const TrackingReport report = odometry.Track(ReadFrame(*reader, i));
      ASSERT_NE(report.status, TrackingStatus::kLost) << report.why;
    }
    keyframes = odometry.num_keyframes();
    // Moved while its worker runs: the worker keeps working on the same state.
    RgbdOdometry moved = std::move(odometry);
    ASSERT_NE(moved.Track(ReadFrame(*reader, 60)).status, TrackingStatus::kLost);
  }  // destroyed with searches queued: joins its worker, drops the rest
  EXPECT_GE(keyframes, 5);
}

TEST(RgbdOdometry, AppearanceFindsLoopsWhereThePoseEstimateDoesNotLook) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  // Out and back over frames 0..179. The search near the pose estimate is shrunk to nothing, as
  // when drift has carried the estimate far from where the camera really is: only appearance
  // can propose the old keyframes.
  std::vector<RgbdFrame> frames;
  for (std::size_t i = 0; i < 180; i += 3) frames.push_back(ReadFrame(*reader, i));
  for (int i = 178; i > 0; i -= 3) frames.push_back(ReadFrame(*reader, static_cast<std::size_t>(i)));
  for (const int appearance : {0, 2}) {
    OdometryConfig config;
    config.loop_search_radius_m = 1e-6;
    config.loop_appearance_candidates = appearance;
    RgbdOdometry odometry(config);
    for (const RgbdFrame& frame : frames) {
      ASSERT_NE(odometry.Track(frame).status, TrackingStatus::kLost) << frame.name;
    }
    std::printf("appearance candidates %d: %d loops\n", appearance, odometry.loops_closed());
    if (appearance == 0) {
      EXPECT_EQ(odometry.loops_closed(), 0);
    } else {
      EXPECT_GE(odometry.loops_closed(), 1);
    }
  }
}

TEST(RgbdOdometry, AStreamWithEstimatedPosesGivesEachFrameTheTrackedPose) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  auto log = std::make_shared<EstimatedTrajectory>();
  auto stream = WithEstimatedPoses(MakeSequenceStream(*reader, 0, 60), OdometryConfig{}, log);
  RgbdFrame frame;
  FrameStatus status;
  std::vector<Eigen::Isometry3d> streamed;
  while ((status = stream->Next(&frame, &why)) == FrameStatus::kFrame) streamed.push_back(frame.T_W_C);
  ASSERT_EQ(status, FrameStatus::kEnded) << why;
  ASSERT_EQ(log->frames, 60);
  ASSERT_EQ(log->estimated.size(), 60u);
  ASSERT_EQ(streamed.size(), 60u);
  // The stream replaced the dataset's poses by the estimate; the dataset's are kept to score.
  EXPECT_TRUE(streamed[0].isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_FALSE(log->source[0].T_W_C.isApprox(Eigen::Isometry3d::Identity()));
  const std::vector<TrajectoryPose> final_poses = FinalPoses(*log);
  ASSERT_EQ(final_poses.size(), 60u);
  for (std::size_t i = 0; i < 60; ++i) {
    EXPECT_TRUE(streamed[i].isApprox(log->estimated[i].T_W_C));
    // No loop in 2 s: the final poses are the tracked ones.
    EXPECT_LT((final_poses[i].T_W_C.inverse() * streamed[i]).translation().norm(), 1e-6);
  }
  TrajectoryErrors errors;
  ASSERT_TRUE(EvaluateTrajectory(log->estimated, log->source, {}, &errors, &why)) << why;
  EXPECT_LT(errors.ate_rmse_m, 0.02);
}

TEST(RgbdOdometry, ConfigIsValidated) {
  std::string why;
  EXPECT_TRUE(OdometryConfig{}.IsValid(&why)) << why;
  OdometryConfig config;
  config.min_inliers = 3;
  EXPECT_FALSE(config.IsValid(&why));
  config = OdometryConfig{};
  config.max_depth_m = 0.1;
  EXPECT_FALSE(config.IsValid(&why));
  config = OdometryConfig{};
  config.keyframe_min_inliers = 10;
  EXPECT_FALSE(config.IsValid(&why));
  config = OdometryConfig{};
  config.depth_refinement_fine_step = 0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("depth_refinement"), std::string::npos) << why;
  config.depth_refinement = false;  // the dense step's settings matter only when it runs
  EXPECT_TRUE(config.IsValid(&why)) << why;
  config = OdometryConfig{};
  config.edge_feature_sigma_deg = 0.0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("sigma"), std::string::npos) << why;
}

TEST(RgbdOdometry, EdgesCarryTheInformationOfTheirAlignment) {
  const std::string folder = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(folder);
  std::string why;
  auto reader = OpenSequence(folder, &why);
  ASSERT_NE(reader, nullptr) << why;
  std::vector<RgbdFrame> frames;
  for (std::size_t i = 0; i < 90; i += 3) frames.push_back(ReadFrame(*reader, i));
  for (const bool from_alignment : {true, false}) {
    OdometryConfig config;
    config.edge_information_from_alignment = from_alignment;
    RgbdOdometry odometry(config);
    for (const RgbdFrame& frame : frames) {
      ASSERT_NE(odometry.Track(frame).status, TrackingStatus::kLost) << frame.name;
    }
    ASSERT_GE(odometry.graph_edges().size(), 3u);
    const double floor_m = 1.0 / (config.edge_sigma_m * config.edge_sigma_m);
    const double features_m = 1.0 / (config.edge_feature_sigma_m * config.edge_feature_sigma_m);
    int coupled = 0;
    for (const PoseGraphEdge& edge : odometry.graph_edges()) {
      const Eigen::LLT<Eigen::Matrix<double, 6, 6>> cholesky(edge.information);
      EXPECT_EQ(cholesky.info(), Eigen::Success);
      const Eigen::Matrix<double, 6, 6> off_diagonal =
          edge.information - Eigen::Matrix<double, 6, 6>(edge.information.diagonal().asDiagonal());
      coupled += off_diagonal.norm() > 1e-6 * edge.information.norm();
      for (int i = 0; i < 3; ++i) {
        if (from_alignment) {
          // At least the features' share, at most the depth's floor and the features' together.
          EXPECT_GE(edge.information(i, i), 0.99 * features_m);
          EXPECT_LE(edge.information(i, i), 1.01 * (floor_m + features_m));
        } else {
          EXPECT_NEAR(edge.information(i, i), floor_m, 1e-6 * floor_m);
        }
      }
    }
    // The depth's Hessian couples translation and rotation (the scene is off the camera's axis);
    // the fixed sigmas do not.
    if (from_alignment) {
      EXPECT_GT(coupled, 0);
    } else {
      EXPECT_EQ(coupled, 0);
    }
  }
}

}  // namespace
}  // namespace objmap
