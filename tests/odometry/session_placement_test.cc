// Placing a session that sees the mapped room from farther back and higher than any stored view
// (objmap_sim's second sessions): each map keyframe alone shares too few features with its
// frames to place them, the look-alike keyframes' points together do
// (OdometryConfig::relocalisation_map_candidates).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "odometry/rgbd_odometry.h"
#include "sim/renderer.h"
#include "sim/revisit.h"
#include "sim/scene.h"

namespace objmap {
namespace {

constexpr int kFrames = 300;

double AngleDeg(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(T.linear()).angle() * 180.0 / M_PI;
}

RgbdFrame RenderFrame(const sim::Scene& scene, int index) {
  const Eigen::Isometry3d& T_W_C = scene.trajectory[static_cast<std::size_t>(index)];
  sim::RenderedFrame rendered =
      sim::Render(scene, T_W_C, sim::DepthNoiseConfig{}, scene.seed, index);
  RgbdFrame frame;
  frame.frame_index = index;
  frame.name = scene.kind + " frame " + std::to_string(index);
  frame.color = std::move(rendered.color);
  frame.depth = std::move(rendered.depth);
  frame.intrinsics = scene.intrinsics;
  frame.T_W_C = T_W_C;
  return frame;
}

struct PlacementRun {
  int placed_at = -1;                      // index into the session's frames, -1: never placed
  double error_cm = 0.0, error_deg = 0.0;  // of the frame that placed it
};

PlacementRun PlaceSession(const std::vector<RgbdFrame>& map, const std::vector<RgbdFrame>& session,
                          const OdometryConfig& config) {
  RgbdOdometry odometry(config);
  for (const RgbdFrame& keyframe : map) {
    std::string why;
    EXPECT_TRUE(odometry.AddMapKeyframe(keyframe, &why)) << why;
  }
  PlacementRun run;
  for (std::size_t i = 0; i < session.size(); ++i) {
    const TrackingReport report = odometry.Track(session[i]);
    if (report.status == TrackingStatus::kLost) continue;
    if (report.fragment == 0 && report.status != TrackingStatus::kProvisional) {
      const Eigen::Isometry3d error = session[i].T_W_C.inverse() * report.T_W_C;
      run.placed_at = static_cast<int>(i);
      run.error_cm = 100.0 * error.translation().norm();
      run.error_deg = AngleDeg(error);
      break;
    }
  }
  return run;
}

struct RevisitFrames {
  std::vector<RgbdFrame> map;      // every 10th frame of the first session, at its poses
  std::vector<RgbdFrame> session;  // the second session's first frames, every 2nd
};

RevisitFrames MakeRevisitFrames(const std::string& kind, std::uint64_t seed, int session_frames) {
  sim::Scene first, second;
  sim::SceneChanges changes;
  std::string why;
  RevisitFrames frames;
  EXPECT_TRUE(sim::MakeScene(kind, seed, kFrames, &first, &why)) << why;
  EXPECT_TRUE(
      sim::MakeRevisit(first, sim::RevisitConfig{}, seed + 1, kFrames, &second, &changes, &why))
      << why;
  if (first.trajectory.empty() || second.trajectory.empty()) return frames;
  for (int i = 0; i < kFrames; i += 10) frames.map.push_back(RenderFrame(first, i));
  for (int i = 0; i < 2 * session_frames; i += 2) frames.session.push_back(RenderFrame(second, i));
  return frames;
}

// Procedural scenes (no catalog meshes: the same on every machine) where no keyframe alone
// places the first frames of the second session.
TEST(SessionPlacement, TheLookAlikesTogetherPlaceAViewFromFartherBackThanAnyKeyframe) {
  for (const auto& [kind, seed] : {std::pair<std::string, std::uint64_t>{"desk", 2},
                                   std::pair<std::string, std::uint64_t>{"office", 3}}) {
    SCOPED_TRACE(kind + " seed " + std::to_string(seed));
    const RevisitFrames frames = MakeRevisitFrames(kind, seed, 4);
    ASSERT_EQ(frames.session.size(), 4u);
    OdometryConfig single_keyframes;
    single_keyframes.relocalisation_map_candidates = 0;
    EXPECT_EQ(PlaceSession(frames.map, frames.session, single_keyframes).placed_at, -1)
        << "a single keyframe placed the session: the scene no longer tests the look-alikes "
           "together";
    const PlacementRun run = PlaceSession(frames.map, frames.session, OdometryConfig{});
    ASSERT_GE(run.placed_at, 0) << "never placed";
    EXPECT_LT(run.error_cm, 2.0);
    EXPECT_LT(run.error_deg, 1.0);
  }
}

// A session of another room (a kitchen's second session against a desk's map) is never placed,
// whatever its frames share with the map's by chance.
TEST(SessionPlacement, ASessionOfAnotherRoomIsNotPlacedByTheLookAlikesTogether) {
  const RevisitFrames desk = MakeRevisitFrames("desk", 2, 0);
  const RevisitFrames kitchen = MakeRevisitFrames("kitchen", 2, 12);
  ASSERT_EQ(kitchen.session.size(), 12u);
  EXPECT_EQ(PlaceSession(desk.map, kitchen.session, OdometryConfig{}).placed_at, -1);
}

}  // namespace
}  // namespace objmap
