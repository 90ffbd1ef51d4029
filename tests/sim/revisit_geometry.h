#pragma once
// The geometry a revisit is planned with: objects' world boxes, the surfaces things stand on,
// where a camera sees a point, and the second session's trajectory.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/sim_random.h"

namespace objmap::sim {

/// An axis-aligned box in the world frame.
struct WorldBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
};

/// The world box around the object's mesh bounds (their 8 corners moved by T_W_O).
[[nodiscard]] WorldBox ObjectWorldBox(const SceneObject& object);
/// The centre of the object's box as ground_truth.json gives it: T_W_O times the centre of the
/// mesh bounds.
[[nodiscard]] Eigen::Vector3d ObjectBoxCentre(const SceneObject& object);

/// True when `a` and `b` come closer than `gap_m` horizontally while overlapping by more than
/// `touch_m` vertically: a cup standing on a table touches its box without clashing.
[[nodiscard]] bool BoxesClash(const WorldBox& a, const WorldBox& b, double gap_m, double touch_m);

/// A horizontal rectangle objects can stand on.
struct SupportSurface {
  Eigen::Vector2d min_xy = Eigen::Vector2d::Zero(), max_xy = Eigen::Vector2d::Zero();
  double z = 0.0;
  bool floor = false;
  int object_id = 0;  ///< the table it is the top of; 0 for the room's structure
};

struct RoomLayout {
  std::vector<SupportSurface> supports;  ///< the floor first
  /// The structure standing on the floor (counters, shelves, walls), up to its top.
  std::vector<WorldBox> obstacles;
};

/// The floor (the lowest upward face of the structure), counters (upward structure faces 0.3 to
/// 1.3 m above the floor) and the tops of the scene's dining tables. False when the structure
/// has no floor.
[[nodiscard]] bool FindRoomLayout(const Scene& scene, RoomLayout* layout, std::string* why);

/// The index of the highest support under the box's centre that its bottom rests on (within
/// 2 cm) or stands above (on something standing on it); -1 when none.
[[nodiscard]] int SupportUnder(const RoomLayout& layout, const WorldBox& box);

/// How many poses of `trajectory` see `point_W` in front of the camera, inside the image and
/// within `max_m`.
[[nodiscard]] int FramesInView(const Eigen::Vector3d& point_W,
                               const std::vector<Eigen::Isometry3d>& trajectory,
                               const CameraIntrinsics& K, double max_m);

/// A trajectory of `frames` poses over the room of `first`: it starts over the middle of the
/// first sweep (looking where the first session looked most), farther away and higher, swings
/// to one side and then across to the other, as long as the first sweep, so that frame to frame
/// it moves no more than the first. Eyes stay 0.3 m inside `floor`. Empty when `first` is.
[[nodiscard]] std::vector<Eigen::Isometry3d> RevisitTrajectory(
    const std::vector<Eigen::Isometry3d>& first, const SupportSurface& floor, int frames,
    Random* random);

/// The first session's path driven again, as a robot on a patrol route does: `frames` poses
/// along it, each off by a slow drift of up to `offset_m` and `offset_deg` (not frame-to-frame
/// noise: a route followed a little to one side). Empty when `first` is.
[[nodiscard]] std::vector<Eigen::Isometry3d> PatrolTrajectory(
    const std::vector<Eigen::Isometry3d>& first, int frames, double offset_m, double offset_deg,
    Random* random);

}  // namespace objmap::sim
