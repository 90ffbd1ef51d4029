#pragma once
// Private to map_server: turns the mapper's mutable object map into immutable snapshots.

#include <array>
#include <map>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include "map_server/map_server.h"

namespace objmap {

/// Builds snapshots on the mapping thread, reusing the views (and point models) of objects that
/// did not change, and remembers which classes changed at which version (Inventory since).
/// Thread-safety: none (mapping thread only); the snapshots it returns are immutable.
class SnapshotBuilder {
 public:
  /// What changed between the previous snapshot and this one.
  struct Diff {
    /// Published ids (a moved object's first id).
    std::vector<ObjectId> added, updated, removed;
    /// The mapper's ids of the present objects in `added` and `updated` (the store's).
    std::vector<ObjectId> changed_objects;
    /// Object changes listed for the first time.
    std::vector<MapObjectChange> object_changes;
  };

  /// A snapshot of `mapper` at `version`; `diff` (may be null) receives the object changes.
  std::shared_ptr<const MapSnapshot> Build(const Mapper& mapper, std::uint64_t version, Diff* diff);

  /// The session and stamp of a keyframe, for the objects' first and last sightings: every
  /// keyframe before the Build that first shows an observation of it.
  void AddKeyframe(KeyframeId id, SessionId session_id, double stamp_s);
  /// The keyframe's session and stamp (unknown ones: 0).
  [[nodiscard]] ObjectSeen Seen(KeyframeId id) const;
  /// The view of keyframe `id` was seen again (a revisit) in this session at this stamp: the
  /// objects it observed were last seen then, if that is later than what they know.
  void AddRevisit(KeyframeId id, SessionId session_id, double stamp_s);

 private:
  std::shared_ptr<ObjectView> MakeView(const ObjectMap& objects, const MapObject& object,
                                       bool confirmed, bool same_model, KeyframeId last_absent,
                                       std::uint64_t version,
                                       const std::shared_ptr<const ObjectView>& previous);
  /// Sets the view's published id, state, places and addition from its history (may be null).
  void ApplyHistory(const ObjectHistory* history, ObjectId published_id, ObjectView* view) const;
  [[nodiscard]] ObjectPlaceView PlaceView(const ObjectPlace& place) const;
  /// The object's last sighting: its newest observation's keyframe, or a later revisit of the
  /// view of one of its observations' keyframes.
  [[nodiscard]] ObjectSeen LastSeen(const MapObject& object) const;
  /// The changes of `changes` with the version each was first listed at; new ones go to `diff`.
  std::vector<MapObjectChange> ListChanges(const ObjectChanges& changes, std::uint64_t version,
                                           Diff* diff);
  void Touch(int class_id, std::uint64_t version);

  std::map<ObjectId, std::shared_ptr<const ObjectView>> views_;  // by published id
  std::map<ObjectId, std::shared_ptr<const ObjectView>> tombstones_;
  // Published id -> the mapper's object its view (or tombstone) was made from.
  std::map<ObjectId, ObjectId> view_sources_;
  // (kind, published id, keyframe) of each change listed so far -> the version it was listed at.
  std::map<std::tuple<int, ObjectId, KeyframeId>, std::uint64_t> change_versions_;
  std::map<KeyframeId, ObjectSeen> keyframes_;
  // Keyframe -> its newest revisit (ObjectSeen of the revisit's session and stamp).
  std::map<KeyframeId, ObjectSeen> revisits_;
  // ObjectMap::ModelKey behind each view's model.
  std::map<ObjectId, std::vector<std::pair<ObjectId, std::uint64_t>>> model_keys_;
  std::array<std::uint64_t, kNumObjectClasses> class_changed_version_{};
  /// Unknown objects are in the inventory (InventoryConfig::count_unknown): their changes are
  /// inventory changes.
  bool count_unknown_ = false;
};

}  // namespace objmap
