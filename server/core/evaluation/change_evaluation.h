#pragma once
// Scoring change detection between two sessions of a map: the changes a map reports (objects
// removed, moved, added) against the changes the scene really went through. Each kind is scored
// on its own (true and false positives, misses) and pooled; for moves, also whether the map kept
// the moved object's identity.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "evaluation/evaluation.h"
#include "types/frame.h"

namespace objmap {

enum class ChangeKind { kRemoved = 0, kMoved = 1, kAdded = 2 };
inline constexpr int kNumChangeKinds = 3;
inline constexpr std::array<ChangeKind, kNumChangeKinds> kChangeKinds = {
    ChangeKind::kRemoved, ChangeKind::kMoved, ChangeKind::kAdded};

/// "removed", "moved", "added": the names both change files use.
[[nodiscard]] std::string_view ChangeKindName(ChangeKind kind);

/// A change the scene went through between two sessions (the simulator's changes.json).
struct GroundTruthChange {
  ChangeKind kind = ChangeKind::kAdded;
  int id = 0;  ///< the object's ground-truth id
  int class_id = -1;
  /// Centre of the object's box: where it is now (added, moved) or was (removed).
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d from_W = Eigen::Vector3d::Zero();  ///< moved only: where it was
  /// The object's largest box extent; 0 when no ground-truth file gave its size.
  double largest_size_m = 0.0;
  /// Frames of the second session that showed it where it is now (-1: not known); see
  /// GroundTruthObject::visible_frames. Known only for objects present in the second session.
  int visible_frames = -1;
  /// What the object looks like, to tell look-alikes (see LookAlike): its surface mesh's vertex
  /// and triangle counts (0: no mesh given) and its box size.
  int mesh_vertices = 0;
  int mesh_triangles = 0;
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
};

/// Two changes are of look-alike objects when nothing but their place tells them apart: the same
/// class, the same surface mesh (vertex and triangle counts) and the same box size within 5 mm
/// per side. Changes without a mesh are never look-alikes.
[[nodiscard]] bool LookAlike(const GroundTruthChange& a, const GroundTruthChange& b);

/// A change a map reports (the map folder's changes.json).
struct ReportedChange {
  ChangeKind kind = ChangeKind::kAdded;
  ObjectId object_id = 0;        ///< the map's own id, not a ground-truth id
  int class_id = -1;             ///< a COCO class or kUnknownClassId
  std::int64_t session_id = -1;  ///< the session that saw the change (-1: not given)
  KeyframeId keyframe_id = -1;   ///< the keyframe that showed the change (-1: not given)
  double stamp = 0.0;
  /// Where the object is now (added, moved) or was (removed).
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d from_W = Eigen::Vector3d::Zero();  ///< moved only: its previous place
  Eigen::Vector3d min_W = Eigen::Vector3d::Zero();   ///< its model's bounds (zero: not given)
  Eigen::Vector3d max_W = Eigen::Vector3d::Zero();
};

struct ChangeEvaluationConfig {
  /// A report matches a real change of its kind and class when its position (for moves: both
  /// its previous and its present place) lies within max(min_match_distance_m,
  /// size_share * the object's largest extent) of the real one: centroids of partly seen objects
  /// lie off the box centre by up to half the object, and small objects need a floor since the
  /// detection of a change is coarser than the object.
  double min_match_distance_m = 0.25;
  double size_share = 0.5;
  /// Only reports of sessions with an id >= this count (the sessions whose changes are being
  /// scored); 0 counts every session (session ids start at 1). Reports without a session id
  /// are left out when this is > 0.
  std::int64_t min_session_id = 0;
  /// Real changes whose object the second session showed in fewer frames than this (when its
  /// ground truth says) are left out, counted as unseen: no map can report what it never saw.
  int min_visible_frames = 1;
  /// Look-alike objects are interchangeable: a cup taken from the desk and the same cup (the same
  /// mesh) put on the shelf read as well as "the cup moved to the shelf", and of two identical
  /// mugs, which one moved and which one arrived cannot be seen. For each group of look-alikes the
  /// real changes are read in the way that matches the reports best: the places the group emptied
  /// (removals, moves' old places) paired with the places it filled (additions, moves' new
  /// places) into moves differently, never into fewer moves than the ground truth has (a move
  /// reported as a removal and an addition stays a missed move). false: as written.
  bool lookalikes_interchangeable = true;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The figures of one kind of change, or of all kinds pooled.
struct ChangeCounts {
  int real = 0;             ///< real changes (unseen ones left out)
  int reported = 0;         ///< reports of a named class (of the sessions counted)
  int true_positives = 0;   ///< real changes a report matches
  int false_positives = 0;  ///< reports that match no real change
  int misses = 0;           ///< real changes no report matches
  int unseen = 0;           ///< real changes of objects the second session never showed
  /// Reports of objects of class unknown: no class to match, counted apart (as the object
  /// evaluation counts unknown objects apart).
  int unknown_class = 0;

  [[nodiscard]] double Precision() const;  ///< TP / (TP + FP); 1 when nothing is reported
  [[nodiscard]] double Recall() const;     ///< TP / real; 1 when nothing changed
  void Add(const ChangeCounts& other);
};

/// A real change and the report that matches it.
struct ChangeMatch {
  ChangeKind kind = ChangeKind::kAdded;
  int real_id = 0;
  ObjectId object_id = 0;
  /// For moves: the map still holds, under the id it reported moving, an object now (see
  /// EvaluateChanges). Always false for the other kinds.
  bool kept_id = false;
};

struct ChangeEvaluation {
  std::array<ChangeCounts, kNumChangeKinds> per_kind;  ///< indexed by ChangeKind
  ChangeCounts totals;
  std::vector<ChangeMatch> matches;
  /// Real moves (not unseen) and those whose object kept its id.
  int moved_total = 0;
  int moved_kept_id = 0;
  /// Real moves the map missed as a move but reported as a removal at the old place and an
  /// addition at the new one (both also counted as false positives of their kinds).
  int moved_as_removed_and_added = 0;
  /// Groups of look-alike objects whose changes were read otherwise than the ground truth writes
  /// them (ChangeEvaluationConfig::lookalikes_interchangeable); the counts above are of that
  /// reading.
  int lookalike_groups_reread = 0;

  [[nodiscard]] const ChangeCounts& Of(ChangeKind kind) const {
    return per_kind[static_cast<int>(kind)];
  }
};

/// Sets each change's largest_size_m (and visible_frames) from the ground truth of the session
/// before the changes (`before`: removed objects, moved ones at their old place) and after them
/// (`after`: added and moved objects); either may be empty. Returns the ids of changes that the
/// given files should hold but do not: a sign of the wrong files; those keep the distance floor.
[[nodiscard]] std::vector<int> AttachGroundTruthSizes(const std::vector<GroundTruthObject>& before,
                                                      const std::vector<GroundTruthObject>& after,
                                                      std::vector<GroundTruthChange>* changes);

/// Scores `reported` against `real`. Per kind, each report may match one real change of its
/// kind and class within the distance of ChangeEvaluationConfig, nearest pairs first (for moves
/// the larger of the two distances). A real move matched by one "moved" report kept its id when
/// `present` (the objects the map claims now) holds an object with the reported id: a map that
/// reports a move of object 12 but now holds the object as number 30 did not keep it. A move
/// reported as a removal and an addition is a missed move and two false positives: the map lost
/// the object's identity, which a move keeps.
/// `present` may be null: ids are then not checked, and every matched move kept its id.
/// Changes of look-alike objects are read as ChangeEvaluationConfig::lookalikes_interchangeable
/// says.
[[nodiscard]] ChangeEvaluation EvaluateChanges(const std::vector<GroundTruthChange>& real,
                                               const std::vector<ReportedChange>& reported,
                                               const std::vector<MappedObject>* present,
                                               const ChangeEvaluationConfig& config);

}  // namespace objmap
