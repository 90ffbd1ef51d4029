#pragma once
// Private to map_server: turns the mapper's mutable object map into immutable snapshots.

#include <array>
#include <map>
#include <memory>
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
    std::vector<ObjectId> added, updated, removed;
  };

  /// A snapshot of `mapper` at `version`; `diff` (may be null) receives the object changes.
  std::shared_ptr<const MapSnapshot> Build(const Mapper& mapper, std::uint64_t version, Diff* diff);

  /// The session and stamp of a keyframe, for the objects' first and last sightings: every
  /// keyframe before the Build that first shows an observation of it.
  void AddKeyframe(KeyframeId id, SessionId session_id, double stamp_s);

 private:
  std::shared_ptr<const ObjectView> MakeView(const ObjectMap& objects, const MapObject& object,
                                             bool confirmed, bool same_model, KeyframeId last_absent,
                                             std::uint64_t version,
                                             const std::shared_ptr<const ObjectView>& previous);
  /// The keyframe's session and stamp (unknown ones: 0).
  [[nodiscard]] ObjectSeen Seen(KeyframeId id) const;
  void Touch(int class_id, std::uint64_t version);

  std::map<ObjectId, std::shared_ptr<const ObjectView>> views_;
  std::map<KeyframeId, ObjectSeen> keyframes_;
  // ObjectMap::ModelKey behind each view's model.
  std::map<ObjectId, std::vector<std::pair<ObjectId, std::uint64_t>>> model_keys_;
  std::array<std::uint64_t, kNumObjectClasses> class_changed_version_{};
  /// Unknown objects are in the inventory (InventoryConfig::count_unknown): their changes are
  /// inventory changes.
  bool count_unknown_ = false;
};

}  // namespace objmap
