#pragma once
// Private to map_server: conversions between the mapper's state and the store's rows.

#include <optional>
#include <set>

#include "mapper/mapper.h"
#include "store/keyframe_store.h"

namespace objmap {

/// The store's row for a keyframe the mapper has just added (colour kept when it matches the
/// intrinsics; detections as given).
[[nodiscard]] StoredKeyframe MakeStoredKeyframe(const RgbdFrame& frame,
                                                const std::vector<Detection>& detections,
                                                KeyframeId id, const KeyframeRecord& record);

/// Rebuilds `mapper` from everything stored, the OctoMap from the checkpoint when it is usable
/// (Mapper::Restore); `known_keyframes` receives the keyframe ids.
RestoreOutcome RestoreMapper(StoredMap stored, std::optional<StoredCheckpoint> checkpoint,
                             Mapper* mapper, std::set<KeyframeId>* known_keyframes);

}  // namespace objmap
