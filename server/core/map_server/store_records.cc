#include "map_server/store_records.h"

namespace objmap {

StoredKeyframe MakeStoredKeyframe(const RgbdFrame& frame, const std::vector<Detection>& detections,
                                  KeyframeId id, const KeyframeRecord& record) {
  StoredKeyframe stored;
  stored.id = id;
  stored.stamp_s = frame.stamp_s;
  stored.name = frame.name;
  stored.T_W_C = record.T_W_C;
  stored.intrinsics = record.intrinsics;
  stored.depth_mm = record.depth_mm;
  stored.object_mask = record.object_mask;
  if (frame.color.width == record.intrinsics.width &&
      frame.color.height == record.intrinsics.height && !frame.color.empty()) {
    stored.color = frame.color;
  }
  stored.detections = detections;
  return stored;
}

RestoreOutcome RestoreMapper(StoredMap stored, std::optional<StoredCheckpoint> checkpoint,
                             Mapper* mapper, std::set<KeyframeId>* known_keyframes) {
  std::map<KeyframeId, KeyframeRecord> records;
  for (StoredKeyframe& keyframe : stored.keyframes) {
    KeyframeRecord& record = records[keyframe.id];
    record.T_W_C = keyframe.T_W_C;
    record.intrinsics = keyframe.intrinsics;
    record.depth_mm = std::move(keyframe.depth_mm);
    record.object_mask = std::move(keyframe.object_mask);
    record.session = keyframe.session_id;
    known_keyframes->insert(keyframe.id);
  }
  std::map<ObjectId, std::vector<ObjectObservation>> observations;
  for (StoredObservation& row : stored.observations) {
    observations[row.object_id].push_back(std::move(row.observation));
  }
  if (!checkpoint) {
    return mapper->Restore(std::move(records), std::move(observations), stored.next_object_id);
  }
  OccupancyCheckpoint occupancy{std::move(checkpoint->occupancy_state),
                                std::move(checkpoint->keyframe_poses)};
  return mapper->Restore(std::move(records), std::move(observations), stored.next_object_id,
                         &occupancy);
}

}  // namespace objmap
