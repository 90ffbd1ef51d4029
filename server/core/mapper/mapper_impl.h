#pragma once

// The Mapper's state, shared by the files that implement it (mapper.cc: keyframes, poses and
// regeneration; mapper_inventory.cc: evidence, changes and the inventory). Not for other folders.

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>

#include "mapper/mapper.h"
#include "occupancy/shared_occupancy_map.h"

namespace objmap {

struct Mapper::Impl {
  explicit Impl(const MapperConfig& c)
      : config(c),
        segmenter(c.segmenter),
        associator(c.association),
        objects(c.objects),
        occupancy(c.occupancy, c.occupancy_second_copy) {}

  MapperConfig config;
  Segmenter segmenter;
  Associator associator;
  ObjectMap objects;
  // Written here, read by ReadOccupancy on any thread.
  SharedOccupancyMap occupancy;
  std::map<KeyframeId, KeyframeRecord> keyframes;
  KeyframeId next_keyframe_id = 1;

  // Camera-frame reach of each keyframe's rays (ReachInCameraFrame), filled when first needed.
  std::map<KeyframeId, Eigen::AlignedBox3d> reach_C;

  // What each keyframe sees of each object, for its evidence: valid for one model version of the
  // object and the keyframes' current poses (cleared when poses change). Keyframes are evaluated
  // once each, in id order, so an unchanged object costs only the keyframes added since.
  struct ObjectVisibilityCache {
    std::uint64_t model_version = 0;
    KeyframeId evaluated_through = 0;
    std::map<KeyframeId, ObjectVisibility> seen;  // keyframes that see some of it
  };
  mutable std::map<ObjectId, ObjectVisibilityCache> visibility_cache;

  const std::map<KeyframeId, ObjectVisibility>& VisibilityOf(const MapObject& object) const;
  // The inventory thresholds, with what the keyframes up to `through` saw of the object.
  bool IsConfirmedThrough(const MapObject& object, KeyframeId through) const;
  void DropStaleVisibility() const;

  // The independent view of every keyframe (ViewGroupingConfig), extended keyframe by keyframe
  // and recomputed when poses change; the first keyframe of the latest view is its anchor.
  std::map<KeyframeId, int> view_of_keyframe;
  KeyframeId view_anchor = 0;
  // The mapping session of keyframes to come (KeyframeRecord::session).
  std::int64_t session = 0;
  int ViewOfNewKeyframe(KeyframeId id, const Eigen::Isometry3d& T_W_C);
  // Regroups every keyframe with its current pose (the objects' observations are not touched).
  void RecomputeViews();

  void Reassociate();
  KeyframePoseLookup PoseLookup() const;
  KeyframeSessionLookup SessionLookup() const;
  void RebuildOccupancy();
  const Eigen::AlignedBox3d& ReachOf(KeyframeId id);
  void RegenerateOccupancy(const std::map<KeyframeId, Eigen::Isometry3d>& old_poses,
                           PoseUpdateReport* report);
  bool RestoreOccupancy(const OccupancyCheckpoint& checkpoint, int* integrated, std::string* why);
};

}  // namespace objmap
