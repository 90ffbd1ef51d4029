#include "mapper/mapper.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>

#include "mapper/keyframe_segments.h"
#include "mapper/mapper_impl.h"
#include "segmentation/segment_index.h"
#include "types/organized_cloud.h"

namespace objmap {
namespace {

using Clock = std::chrono::steady_clock;

// A pose that differs from the current one by less than this is the same pose sent again
// (through text, quaternions or float32 on its way): nothing is regenerated for it.
constexpr double kSamePoseTranslationM = 1e-6;
constexpr double kSamePoseRotationRad = 1e-6;

bool IsSamePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d delta = a.inverse() * b;
  return delta.translation().norm() < kSamePoseTranslationM &&
         Eigen::AngleAxisd(delta.linear()).angle() < kSamePoseRotationRad;
}

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::vector<Eigen::Vector3f> ToWorld(const std::vector<Eigen::Vector3f>& points_C,
                                     const Eigen::Isometry3d& T_W_C) {
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  std::vector<Eigen::Vector3f> points_W;
  points_W.reserve(points_C.size());
  for (const Eigen::Vector3f& p : points_C) points_W.push_back(T * p);
  return points_W;
}

}  // namespace

// The depth image's pixel grid lets the map carve free space block-wise.
DepthScanW DepthScanOf(const KeyframeRecord& record) {
  DepthImage depth;
  depth.width = record.intrinsics.width;
  depth.height = record.intrinsics.height;
  depth.depth_m.reserve(record.depth_mm.size());
  for (std::uint16_t mm : record.depth_mm) depth.depth_m.push_back(DepthSampleMetres(mm));
  OrganizedCloud cloud_C = BackProject(depth, ColorImage{}, record.intrinsics);
  DepthScanW scan;
  scan.T_W_C = record.T_W_C.cast<float>();
  scan.width = cloud_C.width;
  scan.height = cloud_C.height;
  scan.fx = static_cast<float>(record.intrinsics.fx);
  scan.fy = static_cast<float>(record.intrinsics.fy);
  scan.cx = static_cast<float>(record.intrinsics.cx);
  scan.cy = static_cast<float>(record.intrinsics.cy);
  scan.points_C = std::move(cloud_C.points_C);
  scan.object_mask = record.object_mask;
  return scan;
}

std::vector<std::uint16_t> DepthMillimetres(const DepthImage& depth) {
  std::vector<std::uint16_t> depth_mm(depth.depth_m.size());
  for (std::size_t i = 0; i < depth_mm.size(); ++i) {
    depth_mm[i] = DepthSampleMillimetres(depth.depth_m[i]);
  }
  return depth_mm;
}

KeyframeRecord RecordOf(const RgbdFrame& frame) {
  KeyframeRecord record;
  record.T_W_C = frame.T_W_C;
  record.intrinsics = frame.intrinsics;
  record.depth_mm = DepthMillimetres(frame.depth);
  record.object_mask.assign(record.depth_mm.size(), 0);
  return record;
}

namespace {

void MarkObjectPixels(const std::vector<SegmentedDetection>& segmented, KeyframeRecord* record) {
  for (const SegmentedDetection& entry : segmented) {
    for (int i : entry.pixels) record->object_mask[i] = 1;
  }
}

// No object took the observation (AssociateKeyframe).
constexpr ObjectId kNoObject = 0;

// Assigns one keyframe's segments to objects of `map` (or new ones); the observations are moved
// into the map. Returns the object that took each observation, in their order (kNoObject for
// an unclassified one that matched a named object: dropped).
std::vector<ObjectId> AssociateKeyframe(ObjectMap* map, Associator* associator,
                                        std::vector<ObjectObservation>* observations,
                                        const Eigen::Isometry3d& T_W_C, KeyframeResult* result) {
  std::vector<SegmentToAssociate> segments;
  for (const ObjectObservation& observation : *observations) {
    SegmentToAssociate segment;
    segment.points_W = ToWorld(observation.segment_C.points, T_W_C);
    segment.class_id = observation.class_scores.front().first;
    segments.push_back(std::move(segment));
  }
  const auto assignment = associator->AssignKeyframe(*map, segments);
  std::vector<ObjectId> targets;
  for (std::size_t s = 0; s < observations->size(); ++s) {
    ObjectObservation observation = std::move((*observations)[s]);
    // An object-like segment that is part of a named object, in a view where the detector
    // missed it: its model is the detections' to build, and a miss is not a detection.
    if (assignment[s] && IsUnclassified(observation) &&
        map->Find(*assignment[s])->Label() != kUnknownClassId) {
      targets.push_back(kNoObject);
      continue;
    }
    if (assignment[s]) {
      map->AddObservation(*assignment[s], std::move(observation), T_W_C);
      result->updated.push_back(*assignment[s]);
      targets.push_back(*assignment[s]);
    } else {
      result->created.push_back(map->AddObject(std::move(observation), T_W_C));
      targets.push_back(result->created.back());
    }
  }
  return targets;
}

// Duplicates arise when a first partial view did not overlap enough; once the models grow they
// overlap, and the paper's map would keep both (its "duplicate from bad depth" failure).
void MergeDuplicates(ObjectMap* map, Associator* associator, KeyframeResult* result) {
  std::vector<ObjectId> touched = result->created;
  touched.insert(touched.end(), result->updated.begin(), result->updated.end());
  for (const auto& [kept, absorbed] : associator->FindDuplicates(*map, touched)) {
    if (map->Merge(kept, absorbed)) result->merged.emplace_back(kept, absorbed);
  }
  if (!result->merged.empty()) associator->ForgetMissing(*map);
}

// True when the corrections T_new * T_old^-1 of all keyframes agree within the tolerance: the
// whole map moved as one body, and no association changes.
bool IsRigidCorrection(const std::map<KeyframeId, KeyframeRecord>& keyframes,
                       const std::map<KeyframeId, Eigen::Isometry3d>& new_poses,
                       const ReassociationConfig& config) {
  std::optional<Eigen::Isometry3d> reference;
  for (const auto& [id, record] : keyframes) {
    auto it = new_poses.find(id);
    const Eigen::Isometry3d correction =
        it == new_poses.end() ? Eigen::Isometry3d::Identity() : it->second * record.T_W_C.inverse();
    if (!reference) {
      reference = correction;
      continue;
    }
    const Eigen::Isometry3d difference = reference->inverse() * correction;
    if (difference.translation().norm() > config.min_translation_m ||
        Eigen::AngleAxisd(difference.linear()).angle() > config.min_rotation_rad) {
      return false;
    }
  }
  return true;
}

}  // namespace

int Mapper::Impl::ViewOfNewKeyframe(KeyframeId id, const Eigen::Isometry3d& T_W_C) {
  const auto anchor = keyframes.find(view_anchor);
  int view = 0;
  if (anchor != keyframes.end()) {
    view = view_of_keyframe.at(view_anchor);
    if (!config.views.SameView(anchor->second.T_W_C, T_W_C)) {
      ++view;
      view_anchor = id;
    }
  } else {
    view_anchor = id;
  }
  view_of_keyframe[id] = view;
  return view;
}

void Mapper::Impl::RecomputeViews() {
  std::map<KeyframeId, Eigen::Isometry3d> poses;
  for (const auto& [id, record] : keyframes) poses.emplace(id, record.T_W_C);
  view_of_keyframe = IndependentViews(poses, config.views);
  view_anchor = 0;
  if (view_of_keyframe.empty()) return;
  const int last_view = view_of_keyframe.rbegin()->second;
  for (const auto& [id, view] : view_of_keyframe) {
    if (view == last_view) {
      view_anchor = id;
      break;
    }
  }
}

KeyframePoseLookup Mapper::Impl::PoseLookup() const {
  return [this](KeyframeId id) -> std::optional<Eigen::Isometry3d> {
    auto it = keyframes.find(id);
    if (it == keyframes.end()) return std::nullopt;
    return it->second.T_W_C;
  };
}

KeyframeSessionLookup Mapper::Impl::SessionLookup() const {
  return [this](KeyframeId id) -> std::int64_t {
    auto it = keyframes.find(id);
    return it == keyframes.end() ? 0 : it->second.session;
  };
}

// Replays every observation, keyframe by keyframe in id order, through the association with the
// current poses, exactly as AddKeyframe would have met them. An object of the replay takes the id
// of the old object that gave it most of its observations (each old id once, the largest shares
// first); the rest get new ids, so a client's ids stay valid where the object is still the same.
void Mapper::Impl::Reassociate() {
  struct Held {
    ObjectId old_id;
    ObjectObservation observation;
  };
  std::map<KeyframeId, std::vector<Held>> by_keyframe;
  for (const auto& [id, object] : objects.objects()) {
    for (const ObjectObservation& observation : object.observations) {
      by_keyframe[observation.keyframe_id].push_back({id, observation});
    }
  }
  ObjectMap replay(config.objects);
  Associator replay_associator(config.association);
  // For each replayed object: the old ids of its observations, with multiplicity.
  std::map<ObjectId, std::map<ObjectId, int>> sources;
  for (auto& [keyframe_id, held] : by_keyframe) {
    auto keyframe = keyframes.find(keyframe_id);
    if (keyframe == keyframes.end()) continue;  // observations always have their keyframe
    std::vector<ObjectObservation> observations;
    for (Held& h : held) observations.push_back(std::move(h.observation));
    KeyframeResult result;
    const std::vector<ObjectId> targets = AssociateKeyframe(
        &replay, &replay_associator, &observations, keyframe->second.T_W_C, &result);
    for (std::size_t s = 0; s < held.size(); ++s) {
      if (targets[s] != kNoObject) ++sources[targets[s]][held[s].old_id];
    }
    MergeDuplicates(&replay, &replay_associator, &result);
    for (const auto& [kept, absorbed] : result.merged) {
      for (const auto& [old_id, count] : sources[absorbed]) sources[kept][old_id] += count;
      sources.erase(absorbed);
    }
  }

  struct Share {
    int count;
    ObjectId replayed;
    ObjectId old_id;
  };
  std::vector<Share> shares;
  for (const auto& [replayed, counts] : sources) {
    for (const auto& [old_id, count] : counts) shares.push_back({count, replayed, old_id});
  }
  std::sort(shares.begin(), shares.end(), [](const Share& a, const Share& b) {
    if (a.count != b.count) return a.count > b.count;
    return a.replayed != b.replayed ? a.replayed < b.replayed : a.old_id < b.old_id;
  });
  std::map<ObjectId, ObjectId> final_id;  // replayed -> id it keeps
  std::set<ObjectId> old_ids_taken;
  for (const Share& share : shares) {
    if (final_id.count(share.replayed) > 0 || old_ids_taken.count(share.old_id) > 0) continue;
    final_id[share.replayed] = share.old_id;
    old_ids_taken.insert(share.old_id);
  }
  ObjectId next_id = objects.next_id();
  std::map<ObjectId, std::vector<ObjectObservation>> regrouped;
  for (const auto& [replayed, object] : replay.objects()) {
    auto it = final_id.find(replayed);
    const ObjectId id = it != final_id.end() ? it->second : next_id++;
    regrouped[id] = object.observations;
  }
  objects.Restore(std::move(regrouped), next_id, PoseLookup());
  // Ids now name other models: drop the search structures cached for the old ones.
  associator = Associator(config.association);
  visibility_cache.clear();
}

// The checkpoint's OctoMap plus the keyframes after it, when the checkpoint still describes the
// keyframes it holds; false with the reason otherwise (the map is then untouched).
bool Mapper::Impl::RestoreOccupancy(const OccupancyCheckpoint& checkpoint, int* integrated,
                                    std::string* why) {
  const KeyframeId last =
      checkpoint.keyframe_poses.empty() ? 0 : checkpoint.keyframe_poses.rbegin()->first;
  for (const auto& [id, record] : keyframes) {
    if (id > last) break;
    auto it = checkpoint.keyframe_poses.find(id);
    if (it == checkpoint.keyframe_poses.end()) {
      *why = "keyframe " + std::to_string(id) + " is not in the checkpoint";
      return false;
    }
    if (!IsSamePose(it->second, record.T_W_C)) {
      *why = "keyframe " + std::to_string(id) + " moved since the checkpoint";
      return false;
    }
  }
  for (const auto& [id, pose] : checkpoint.keyframe_poses) {
    if (keyframes.count(id) == 0) {
      *why = "the checkpoint holds keyframe " + std::to_string(id) + ", which is not stored";
      return false;
    }
  }
  return occupancy.Rebuild([&](OccupancyMap* map) {
    if (!map->ReadState(checkpoint.state, why)) return false;
    *integrated = 0;
    for (auto it = keyframes.upper_bound(last); it != keyframes.end(); ++it, ++*integrated) {
      map->Integrate(DepthScanOf(it->second));
    }
    return true;
  });
}

void Mapper::Impl::RebuildOccupancy() {
  std::vector<const KeyframeRecord*> records;
  for (const auto& [id, record] : keyframes) records.push_back(&record);
  occupancy.Rebuild([&](OccupancyMap* map) {
    map->IntegrateSequence(
        records.size(), [&records](std::size_t i) { return DepthScanOf(*records[i]); },
        config.regeneration.threads);
    return true;
  });
}

const Eigen::AlignedBox3d& Mapper::Impl::ReachOf(KeyframeId id) {
  auto it = reach_C.find(id);
  if (it != reach_C.end()) return it->second;
  // Two voxels: a voxel holding a point reaches one diagonal beyond it.
  const double margin_m = 2.0 * config.occupancy.resolution_m;
  return reach_C.emplace(id, ReachInCameraFrame(DepthScanOf(keyframes.at(id)), margin_m))
      .first->second;
}

// Rebuilds the OctoMap after the keyframes in `old_poses` moved: only where their rays reach
// (before or after) when few moved, from every keyframe whose rays reach in there, in order.
void Mapper::Impl::RegenerateOccupancy(const std::map<KeyframeId, Eigen::Isometry3d>& old_poses,
                                       PoseUpdateReport* report) {
  const double moved_fraction =
      static_cast<double>(old_poses.size()) / static_cast<double>(keyframes.size());
  if (moved_fraction > config.regeneration.incremental_max_moved_fraction) {
    RebuildOccupancy();
    report->keyframes_reintegrated = static_cast<int>(keyframes.size());
    return;
  }
  // Each moved keyframe's scan as it was and as it is: the space it reached and reaches.
  std::vector<DepthScanW> changed;
  std::vector<Eigen::AlignedBox3d> changed_reach;
  for (const auto& [id, old_pose] : old_poses) {
    const KeyframeRecord& record = keyframes.at(id);
    changed.push_back(DepthScanOf(record));
    changed.push_back(changed.back());
    changed.back().T_W_C = old_pose.cast<float>();
    changed_reach.push_back(ReachInWorld(ReachOf(id), record.T_W_C));
    changed_reach.push_back(ReachInWorld(ReachOf(id), old_pose));
  }
  std::vector<const KeyframeRecord*> reaching;
  for (const auto& [id, record] : keyframes) {
    const Eigen::AlignedBox3d reach = ReachInWorld(ReachOf(id), record.T_W_C);
    if (std::any_of(changed_reach.begin(), changed_reach.end(),
                    [&reach](const Eigen::AlignedBox3d& box) { return reach.intersects(box); })) {
      reaching.push_back(&record);
    }
  }
  occupancy.Rewrite([&](OccupancyMap* map) {
    map->RegenerateWhereReached(
        changed, reaching.size(), [&reaching](std::size_t i) { return DepthScanOf(*reaching[i]); },
        config.regeneration.threads);
    return true;
  });
  report->occupancy_incremental = true;
  report->keyframes_reintegrated = static_cast<int>(reaching.size());
}

Mapper::Mapper(const MapperConfig& config) : impl_(std::make_unique<Impl>(config)) {
  [[maybe_unused]] std::string why;
  assert(config.IsValid(&why));
}

Mapper::~Mapper() = default;

bool Mapper::AddKeyframe(const RgbdFrame& frame, const std::vector<Detection>& detections,
                         KeyframeResult* result, std::string* why) {
  if (!ValidateFrame(frame, why)) return false;
  *result = KeyframeResult{};
  result->keyframe_id = impl_->next_keyframe_id++;

  auto start = Clock::now();
  const OrganizedCloud cloud_C = BackProject(frame.depth, frame.color, frame.intrinsics);
  const SegmentationResult segmentation = impl_->segmenter.Segment(cloud_C);
  // Built once: every detection box then costs its own area, not a pass over the image.
  const SegmentIndex index = IndexSegments(segmentation, cloud_C);
  // The depth as stored: observations' points are made from it, as a restart rebuilds them.
  KeyframeRecord record = RecordOf(frame);
  record.session = impl_->session;
  std::vector<SegmentedDetection> segmented =
      SegmentDetections(frame, cloud_C, record.depth_mm, segmentation, index, detections,
                        result->keyframe_id, impl_->config);
  result->detections_used = static_cast<int>(segmented.size());
  // Unclassified segments stay structure in the OctoMap: the record's mask has the named only.
  MarkObjectPixels(segmented, &record);
  std::vector<SegmentedDetection> unclassified =
      UnclassifiedSegments(frame, cloud_C, record.depth_mm, segmentation, index, detections,
                           segmented, result->keyframe_id, impl_->config);
  result->unclassified_segments = static_cast<int>(unclassified.size());
  for (SegmentedDetection& entry : unclassified) segmented.push_back(std::move(entry));
  result->timings.segmentation_ms = MillisecondsSince(start);

  start = Clock::now();
  const int view = impl_->ViewOfNewKeyframe(result->keyframe_id, frame.T_W_C);
  std::vector<ObjectObservation> observations;
  for (SegmentedDetection& entry : segmented) {
    entry.observation.view = view;
    observations.push_back(std::move(entry.observation));
  }
  AssociateKeyframe(&impl_->objects, &impl_->associator, &observations, frame.T_W_C, result);
  MergeDuplicates(&impl_->objects, &impl_->associator, result);
  result->timings.association_ms = MillisecondsSince(start);

  start = Clock::now();
  impl_->occupancy.Integrate(DepthScanOf(record));
  impl_->keyframes.emplace(result->keyframe_id, std::move(record));
  result->timings.occupancy_ms = MillisecondsSince(start);
  return true;
}

void Mapper::SetSession(std::int64_t session) { impl_->session = session; }

bool Mapper::UpdatePoses(const std::map<KeyframeId, Eigen::Isometry3d>& poses, std::string* why,
                         PoseUpdateReport* report) {
  for (const auto& [id, T_W_C] : poses) {
    if (impl_->keyframes.count(id) == 0) {
      *why = "unknown keyframe id " + std::to_string(id);
      return false;
    }
    std::string reason;
    if (!IsValidRigidTransform(T_W_C.matrix(), &reason)) {
      *why = "keyframe " + std::to_string(id) + ": " + reason;
      return false;
    }
  }
  PoseUpdateReport local_report;
  if (report == nullptr) report = &local_report;
  *report = PoseUpdateReport{};
  report->objects_before = static_cast<int>(impl_->objects.size());
  const ReassociationConfig& reassociation = impl_->config.reassociation;
  const bool reassociate =
      reassociation.enabled && !IsRigidCorrection(impl_->keyframes, poses, reassociation);
  std::set<KeyframeId> moved;
  std::map<KeyframeId, Eigen::Isometry3d> old_poses;
  for (const auto& [id, T_W_C] : poses) {
    KeyframeRecord& record = impl_->keyframes[id];
    if (IsSamePose(record.T_W_C, T_W_C)) continue;
    old_poses[id] = record.T_W_C;
    record.T_W_C = T_W_C;
    moved.insert(id);
  }
  report->keyframes_moved = static_cast<int>(moved.size());
  if (moved.empty()) {
    report->objects_after = report->objects_before;
    return true;
  }
  impl_->visibility_cache.clear();  // seen from other places now
  impl_->RecomputeViews();
  impl_->objects.AssignViews(impl_->view_of_keyframe);
  if (reassociate) {
    impl_->Reassociate();
    report->reassociated = true;
  } else {
    impl_->objects.RebuildObserving(moved, impl_->PoseLookup());
  }
  report->objects_after = static_cast<int>(impl_->objects.size());
  impl_->RegenerateOccupancy(old_poses, report);
  return true;
}

int Mapper::ReassociateObjects() {
  impl_->Reassociate();
  return static_cast<int>(impl_->objects.size());
}

RestoreOutcome Mapper::Restore(std::map<KeyframeId, KeyframeRecord> keyframes,
                               std::map<ObjectId, std::vector<ObjectObservation>> observations,
                               ObjectId next_object_id, const OccupancyCheckpoint* checkpoint) {
  impl_->keyframes = std::move(keyframes);
  impl_->reach_C.clear();
  impl_->visibility_cache.clear();
  impl_->next_keyframe_id = impl_->keyframes.empty() ? 1 : impl_->keyframes.rbegin()->first + 1;
  // Views come from the poses: the observations' stored views (if any) are replaced.
  impl_->RecomputeViews();
  for (auto& [id, list] : observations) AssignViews(impl_->view_of_keyframe, &list);
  impl_->objects.Restore(std::move(observations), next_object_id, impl_->PoseLookup());
  impl_->associator = Associator(impl_->config.association);  // caches of the old objects
  RestoreOutcome outcome;
  if (checkpoint != nullptr && impl_->RestoreOccupancy(*checkpoint, &outcome.keyframes_integrated,
                                                       &outcome.checkpoint_refused)) {
    outcome.from_checkpoint = true;
    return outcome;
  }
  impl_->RebuildOccupancy();
  outcome.keyframes_integrated = static_cast<int>(impl_->keyframes.size());
  return outcome;
}

OccupancyCheckpoint Mapper::MakeOccupancyCheckpoint() const {
  OccupancyCheckpoint checkpoint;
  checkpoint.state = impl_->occupancy.latest().WriteState();
  for (const auto& [id, record] : impl_->keyframes) checkpoint.keyframe_poses[id] = record.T_W_C;
  return checkpoint;
}

const KeyframeRecord* Mapper::FindKeyframe(KeyframeId id) const {
  auto it = impl_->keyframes.find(id);
  return it == impl_->keyframes.end() ? nullptr : &it->second;
}

void Mapper::ReadOccupancy(const std::function<void(const OccupancyMap&)>& read) const {
  impl_->occupancy.Read(read);
}

const ObjectMap& Mapper::objects() const { return impl_->objects; }
const OccupancyMap& Mapper::occupancy() const { return impl_->occupancy.latest(); }
std::size_t Mapper::num_keyframes() const { return impl_->keyframes.size(); }
const MapperConfig& Mapper::config() const { return impl_->config; }

}  // namespace objmap
