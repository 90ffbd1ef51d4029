#pragma once
// What changed in the map over time: objects taken away (their place seen empty after their
// last sighting), objects that appeared where earlier views saw nothing, and objects moved (one
// taken away, one of its label and shape appearing later elsewhere: one object, one id).
//
// Derived from the keyframes and the objects' observations like everything else in the map, so a
// restart, a pose update or a re-association computes the same changes again; nothing about them
// needs storing but the observations that already are.

#include <Eigen/Core>
#include <functional>
#include <map>
#include <set>
#include <vector>

#include "mapper/object_evidence.h"
#include "objects/object_map.h"
#include "types/frame.h"

namespace objmap {

enum class ObjectState {
  kPresent,  ///< where it was first seen
  kRemoved,  ///< its last place was seen empty: a tombstone, out of the inventory and queries
  kMoved,    ///< seen empty at an earlier place and found elsewhere since
};

/// One place an object stood: one object of the ObjectMap (the map keeps an object per place).
struct ObjectPlace {
  ObjectId object = 0;  ///< ObjectMap id of the object at this place
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f min_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f max_W = Eigen::Vector3f::Zero();
  KeyframeId first_seen = 0, last_seen = 0;  ///< its first and last sighting there
  /// The keyframe whose view completed the evidence that the place is empty (ChangeConfig::
  /// min_empty_views after last_seen); 0: not seen empty, it stands there.
  KeyframeId seen_empty_at = 0;
};

/// An object with a change: added, removed or moved (with every place it stood, oldest first).
struct ObjectHistory {
  /// Its id: the smallest ObjectMap id among its places, so that it keeps the id it had before
  /// it moved (a re-association gives the id to the place with most observations, the new one a
  /// fresh, larger id).
  ObjectId id = 0;
  int class_id = -1;
  ObjectState state = ObjectState::kPresent;
  std::vector<ObjectPlace> places;
  /// Its first place was seen empty (ChangeConfig::min_empty_views) before it was first seen
  /// there: it was put there while the map watched. The keyframe of that first sighting; 0: it
  /// was there as far as the map knows (first seen where nothing had looked before).
  KeyframeId added_at = 0;
};

/// The changes of a map, and what they mean for the objects it publishes.
struct ObjectChanges {
  /// Objects with a change, by id.
  std::map<ObjectId, ObjectHistory> histories;
  /// ObjectMap objects whose place was seen empty: removed objects and the old places of moved
  /// ones. They are out of the inventory and of every query of the present map.
  std::set<ObjectId> gone;
  /// ObjectMap id -> the id the object is published under, where they differ (the new place of
  /// a moved object carries the object's first id).
  std::map<ObjectId, ObjectId> published_id;

  /// The id `object` is published under.
  [[nodiscard]] ObjectId PublishedId(ObjectId object) const;
};

/// One change, as the change queries list them.
struct ObjectChange {
  enum class Kind { kAdded, kRemoved, kMoved };
  Kind kind = Kind::kAdded;
  ObjectId id = 0;  ///< the object's published id
  int class_id = -1;
  /// The keyframe whose view completed the evidence for the change.
  KeyframeId keyframe_id = 0;
  /// Where it is (added, moved) or was (removed): centroid and model bounds.
  Eigen::Vector3f centroid_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f min_W = Eigen::Vector3f::Zero();
  Eigen::Vector3f max_W = Eigen::Vector3f::Zero();
  /// Moved: where it was before, and its last sighting there.
  Eigen::Vector3f from_W = Eigen::Vector3f::Zero();
  KeyframeId from_last_seen = 0;
};

[[nodiscard]] const char* ChangeKindName(ObjectChange::Kind kind);
[[nodiscard]] const char* ObjectStateName(ObjectState state);

/// Every change in the histories, ordered by keyframe (then id): each history gives an addition
/// (added_at), one move per later place and a removal when its last place is empty.
[[nodiscard]] std::vector<ObjectChange> ChangeList(const ObjectChanges& changes);

/// What DetectChanges needs of the map.
struct ChangeInputs {
  const ObjectMap* objects = nullptr;
  /// The independent view of every keyframe (ViewGroupingConfig).
  const std::map<KeyframeId, int>* view_of_keyframe = nullptr;
  /// The mapping session of every keyframe (empty: all of one session).
  KeyframeSessionLookup session_of;
  /// What each keyframe saw of an object (keyframes that saw none of it: absent).
  std::function<const std::map<KeyframeId, ObjectVisibility>&(const MapObject&)> visibility_of;
  /// Whether the object passed the inventory thresholds with the keyframes up to `through`
  /// (a removed object counts as what the views up to its removal made of it).
  std::function<bool(const MapObject&, KeyframeId through)> confirmed_through;
};

/// The changes of the map (ChangeConfig). Only named objects change: unknown ones (segmented,
/// never named) are structure a planner avoids, not inventory.
[[nodiscard]] ObjectChanges DetectChanges(const ChangeInputs& inputs, const ChangeConfig& config);

}  // namespace objmap
