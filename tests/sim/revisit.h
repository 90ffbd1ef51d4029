#pragma once
// A second session of a synthetic scene: the same room seen again from another trajectory after
// some objects were taken away, moved elsewhere or brought in, with the truth of what changed,
// for scoring change detection between two visits.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/sequence_writer.h"

namespace objmap::sim {

class FurnitureCatalog;

struct RevisitConfig {
  /// Objects taken away; moved elsewhere (keeping their ids); brought in (with new ids).
  int removed = 3;
  int moved = 3;
  int added = 3;
  /// A moved object's box centre lands at least this far from where it was (metres).
  double min_move_m = 0.5;
  /// Every changed place (the old one of a removed or moved object, the new one of a moved or
  /// added object) has its box centre in view (inside the image, in front of the camera, within
  /// max_view_m) in at least this fraction of the second trajectory's frames, and in at least
  /// 10 of them where it has as many: a change the second session cannot see is not scored.
  double min_view_fraction = 0.4;
  double max_view_m = 4.0;
  /// The second session's path: false, it starts over the middle of the first sweep, farther
  /// away and higher, and swings across the room (RevisitTrajectory); true, it drives the first
  /// session's path again a little to one side (PatrolTrajectory, within patrol_offset_m and
  /// patrol_offset_deg), as a robot on a patrol route does.
  bool patrol = false;
  double patrol_offset_m = 0.03;
  double patrol_offset_deg = 2.0;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// One changed object; positions are box centres (world frame of both sessions' poses, metres).
struct ObjectChange {
  int id = 0;
  int class_id = -1;
  std::string name;
  Eigen::Vector3d from_W = Eigen::Vector3d::Zero();  ///< first session (removed, moved)
  Eigen::Vector3d to_W = Eigen::Vector3d::Zero();    ///< second session (moved, added)
  /// Moved: it stands on another support than before (another table, the floor).
  bool other_support = false;
};

struct SceneChanges {
  std::string kind;
  std::uint64_t scene_seed = 0;    ///< the first session's
  std::uint64_t revisit_seed = 0;  ///< picked the changes and the second trajectory
  std::vector<ObjectChange> removed, moved, added;
};

/// The second session of `first`: the same room and structure, the objects changed as `config`
/// says among those the second trajectory sees well (distinct ones, nothing that carries
/// another object, no table), and `frames` poses of a trajectory that starts over the middle of
/// the first sweep, at another distance and height, and sweeps from there. Moved objects land on
/// a support (one of them on another support than before, where the room has one), added ones
/// are cups, books, bottles, laptops on tables and counters, or chairs and plants on the floor
/// (catalog meshes with a `catalog`); nothing new overlaps an object of either session.
/// Unchanged and moved objects keep their ids, added ones get ids above the first's largest.
/// `second->seed` is `seed`, so its sensor noise and detector draws differ from the first's.
/// False with a reason when `config` is invalid, `first` has no trajectory to revisit, or too
/// few objects can be changed where the second trajectory sees them.
[[nodiscard]] bool MakeRevisit(const Scene& first, const RevisitConfig& config, std::uint64_t seed,
                               int frames, Scene* second, SceneChanges* changes, std::string* why,
                               const FurnitureCatalog* catalog = nullptr);

/// changes.json:
///   {"format": "objmap-changes-1", "kind": "office", "seed": 1, "revisit_seed": 2,
///    "removed": [{"id": 4, "class": "cup", "name": "left cup", "position": [x, y, z]}],
///    "moved": [{"id": 7, "class": "chair", "name": "...", "from": [x, y, z], "to": [x, y, z],
///               "other_support": false}],
///    "added": [{"id": 21, "class": "book", "name": "...", "position": [x, y, z]}]}
/// with COCO class names as in ground_truth.json and box centres in metres.
[[nodiscard]] std::string ChangesJson(const SceneChanges& changes);

/// WriteSequence of the second session into `dir`, then dir/changes.json.
[[nodiscard]] bool WriteRevisitSequence(const Scene& second, const SceneChanges& changes,
                                        const SequenceOptions& options, const std::string& dir,
                                        std::string* why);

}  // namespace objmap::sim
