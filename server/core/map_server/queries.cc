// The read side of MapServer: every query reads one snapshot (objects) or the published OctoMap
// (Mapper::ReadOccupancy), so none waits for a keyframe or a regeneration. Heavy queries
// (QueryOccupancy, GetOctomap) run on the heavy-query threads (FairnessConfig).
#include <algorithm>
#include <cmath>

#include "map_server/map_server_impl.h"

namespace objmap {
namespace {

bool InBox(const Eigen::Vector3f& p, const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W) {
  const Eigen::Vector3d q = p.cast<double>();
  return (q.array() >= min_W.array()).all() && (q.array() <= max_W.array()).all();
}

bool IsFiniteVector(const Eigen::Vector3d& v) { return v.allFinite(); }

// The ray origin + t * direction (unit) meets the box [box_min, box_max] for some t in
// [0, max_t] (slab test).
bool RayMeetsBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                 const Eigen::Vector3d& box_min, const Eigen::Vector3d& box_max, double max_t) {
  double t_enter = 0.0, t_exit = max_t;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(direction[axis]) < 1e-12) {
      if (origin[axis] < box_min[axis] || origin[axis] > box_max[axis]) return false;
      continue;
    }
    double t0 = (box_min[axis] - origin[axis]) / direction[axis];
    double t1 = (box_max[axis] - origin[axis]) / direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    if (t_enter > t_exit) return false;
  }
  return true;
}

// Closed boxes [a_min, a_max] and [b_min, b_max] share a point.
bool BoxesOverlap(const Eigen::Vector3f& a_min, const Eigen::Vector3f& a_max,
                  const Eigen::Vector3d& b_min, const Eigen::Vector3d& b_max) {
  return (a_min.cast<double>().array() <= b_max.array()).all() &&
         (b_min.array() <= a_max.cast<double>().array()).all();
}

}  // namespace

bool ValidateBox(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                 const std::string& field, std::string* why) {
  if (!IsFiniteVector(min_W) || !IsFiniteVector(max_W)) {
    *why = field + ": coordinates must be finite";
    return false;
  }
  static const char* kAxes[] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    if (min_W[axis] > max_W[axis]) {
      *why = field + ".min." + kAxes[axis] + " (" + std::to_string(min_W[axis]) + ") > " + field +
             ".max." + kAxes[axis] + " (" + std::to_string(max_W[axis]) + ")";
      return false;
    }
  }
  return true;
}

ServiceStatus MapServer::QueryObjects(const ObjectFilter& filter,
                                      std::vector<std::shared_ptr<const ObjectView>>* objects,
                                      std::uint64_t* version) const {
  std::string why;
  if (filter.class_id && (*filter.class_id < 0 || *filter.class_id >= kNumObjectClasses)) {
    return ServiceStatus::Invalid("class_id " + std::to_string(*filter.class_id) +
                                  " is not a COCO class (0.." +
                                  std::to_string(kNumCocoClasses - 1) + ") nor unknown (" +
                                  std::to_string(kUnknownClassId) + ")");
  }
  if (filter.region && !ValidateBox(filter.region->first, filter.region->second, "region", &why)) {
    return ServiceStatus::Invalid(why);
  }
  if (filter.nearest_to && !IsFiniteVector(*filter.nearest_to)) {
    return ServiceStatus::Invalid("nearest_to: coordinates must be finite");
  }
  if (!std::isfinite(filter.min_confidence)) {
    return ServiceStatus::Invalid("min_confidence must be finite");
  }
  const auto snapshot = impl_->Current();
  objects->clear();
  for (const auto& [id, view] : snapshot->objects) {
    if (!filter.include_unconfirmed && !view->confirmed) continue;
    if (filter.class_id && view->class_id != *filter.class_id) continue;
    if (view->confidence < filter.min_confidence) continue;
    if (filter.region && !InBox(view->centroid_W, filter.region->first, filter.region->second)) {
      continue;
    }
    objects->push_back(view);
  }
  if (filter.nearest_to) {
    const Eigen::Vector3f point = filter.nearest_to->cast<float>();
    std::stable_sort(objects->begin(), objects->end(), [&](const auto& a, const auto& b) {
      return (a->centroid_W - point).squaredNorm() < (b->centroid_W - point).squaredNorm();
    });
  }
  if (filter.max_results > 0 && objects->size() > filter.max_results) {
    objects->resize(filter.max_results);
  }
  *version = snapshot->version;
  return ServiceStatus::Ok();
}

std::shared_ptr<const ObjectView> MapSnapshot::ObjectOrTombstone(ObjectId id) const {
  if (const auto it = objects.find(id); it != objects.end()) return it->second;
  if (const auto it = tombstones.find(id); it != tombstones.end()) return it->second;
  return nullptr;
}

ServiceStatus MapServer::GetObject(ObjectId id, std::shared_ptr<const ObjectView>* object) const {
  std::shared_ptr<const ObjectView> found = impl_->Current()->ObjectOrTombstone(id);
  if (!found) return ServiceStatus::NotFound("unknown object id " + std::to_string(id));
  *object = std::move(found);
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::ListChanges(const ChangeFilter& filter,
                                     std::vector<MapObjectChange>* changes,
                                     std::uint64_t* version) const {
  if (filter.since_stamp_s && !std::isfinite(*filter.since_stamp_s)) {
    return ServiceStatus::Invalid("since_stamp: not a finite number");
  }
  const auto snapshot = impl_->Current();
  *version = snapshot->version;
  changes->clear();
  for (const MapObjectChange& change : snapshot->changes) {
    if (filter.since_version && change.version <= *filter.since_version) continue;
    if (filter.since_stamp_s && change.seen.stamp_s < *filter.since_stamp_s) continue;
    if (filter.since_session && change.seen.session_id < *filter.since_session) continue;
    changes->push_back(change);
  }
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::Inventory(std::optional<std::uint64_t> since_version,
                                   std::vector<InventoryEntry>* entries,
                                   std::uint64_t* version) const {
  const auto snapshot = impl_->Current();
  *version = snapshot->version;
  if (!since_version) {
    *entries = snapshot->inventory;
    return ServiceStatus::Ok();
  }
  if (*since_version > snapshot->version) {
    return ServiceStatus::Invalid("since_version " + std::to_string(*since_version) +
                                  " is newer than the map (version " +
                                  std::to_string(snapshot->version) + ")");
  }
  entries->clear();
  for (int class_id = 0; class_id < kNumObjectClasses; ++class_id) {
    if (snapshot->class_changed_version[class_id] <= *since_version) continue;
    auto it = std::find_if(snapshot->inventory.begin(), snapshot->inventory.end(),
                           [&](const InventoryEntry& e) { return e.class_id == class_id; });
    if (it != snapshot->inventory.end()) {
      entries->push_back(*it);
    } else {
      InventoryEntry gone;  // changed, and no confirmed object of it is left
      gone.class_id = class_id;
      entries->push_back(gone);
    }
  }
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::Impl::RunHeavy(const std::function<ServiceStatus()>& query) const {
  ServiceStatus status;
  if (!heavy_query_threads->Run([&] { status = query(); })) {
    return {StatusCode::kResourceExhausted,
            "busy: " + std::to_string(config.fairness.max_waiting_heavy_queries) +
                " heavy queries (QueryOccupancy, GetOctomap) already wait "
                "(server.max_waiting_heavy_queries); retry later"};
  }
  return status;
}

ServiceStatus MapServer::QueryOccupancy(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                        double resolution_m, bool list_voxels,
                                        std::size_t max_voxels, RegionOccupancy* region,
                                        std::uint64_t* version) const {
  return impl_->RunHeavy([&] {
    return impl_->ReadRegion(min_W, max_W, resolution_m, list_voxels, max_voxels, region, version);
  });
}

ServiceStatus MapServer::Impl::ReadRegion(const Eigen::Vector3d& min_W,
                                          const Eigen::Vector3d& max_W, double resolution_m,
                                          bool list_voxels, std::size_t max_voxels,
                                          RegionOccupancy* region, std::uint64_t* version) const {
  const ServiceStatus box = CheckQueryBox(min_W, max_W, "region", config.max_query_volume_m3);
  if (!box.ok()) return box;
  if (!std::isfinite(resolution_m) || resolution_m < 0.0) {
    return ServiceStatus::Invalid("resolution must be finite and >= 0");
  }
  const std::size_t limit = std::min<std::size_t>(
      max_voxels == 0 ? config.max_listed_voxels : max_voxels, config.max_listed_voxels);
  *version = Current()->version;
  mapper->ReadOccupancy([&](const OccupancyMap& map) {
    *region = map.QueryRegion(min_W, max_W, resolution_m, list_voxels ? limit : 0);
  });
  return ServiceStatus::Ok();
}

ServiceStatus CheckQueryBox(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                            const std::string& field, double max_volume_m3) {
  std::string why;
  if (!ValidateBox(min_W, max_W, field, &why)) return ServiceStatus::Invalid(why);
  const double volume = (max_W - min_W).prod();
  if (volume > max_volume_m3) {
    return ServiceStatus::Invalid(field + " volume " + std::to_string(volume) + " m^3 exceeds " +
                                  std::to_string(max_volume_m3));
  }
  return ServiceStatus::Ok();
}

bool BoxIsFree(const RegionOccupancy& counts, const std::vector<ObjectId>& objects_inside,
               bool unknown_is_free) {
  return counts.occupied == 0 && objects_inside.empty() && (unknown_is_free || counts.unknown == 0);
}

std::vector<ObjectId> ObjectsInBox(const MapSnapshot& snapshot, const Eigen::Vector3d& min_W,
                                   const Eigen::Vector3d& max_W) {
  std::vector<ObjectId> inside;
  for (const auto& [id, view] : snapshot.objects) {
    if (!BoxesOverlap(view->min_W, view->max_W, min_W, max_W) || !view->model_W) continue;
    const auto& points = view->model_W->points;
    if (std::any_of(points.begin(), points.end(),
                    [&](const Eigen::Vector3f& p) { return InBox(p, min_W, max_W); })) {
      inside.push_back(id);
    }
  }
  return inside;
}

ServiceStatus MapServer::IsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W,
                                bool unknown_is_free, bool* free, RegionOccupancy* counts,
                                std::vector<ObjectId>* objects_inside,
                                std::uint64_t* version) const {
  // Objects from one snapshot; the OctoMap is read live, so the version reported (read by
  // QueryOccupancy) is that snapshot's or a newer one.
  const std::shared_ptr<const MapSnapshot> snapshot = impl_->Current();
  ServiceStatus status = impl_->ReadRegion(min_W, max_W, 0.0, false, 0, counts, version);
  if (!status.ok()) return status;
  std::vector<ObjectId> inside = ObjectsInBox(*snapshot, min_W, max_W);
  *free = BoxIsFree(*counts, inside, unknown_is_free);
  if (objects_inside != nullptr) *objects_inside = std::move(inside);
  return status;
}

ServiceStatus MapServer::CastRay(const Eigen::Vector3d& origin_W,
                                 const Eigen::Vector3d& direction_W, double max_range_m,
                                 bool unknown_stops, RayHit* hit, ObjectId* object_hit,
                                 std::uint64_t* version) const {
  if (!IsFiniteVector(origin_W)) {
    return ServiceStatus::Invalid("origin: coordinates must be finite");
  }
  if (!IsFiniteVector(direction_W) || direction_W.norm() < 1e-9) {
    return ServiceStatus::Invalid("direction must be finite and non-zero");
  }
  if (!std::isfinite(max_range_m) || max_range_m <= 0.0 || max_range_m > 1000.0) {
    return ServiceStatus::Invalid("max_range must be in (0, 1000] metres");
  }
  const std::shared_ptr<const MapSnapshot> snapshot = impl_->Current();
  *version = snapshot->version;
  impl_->mapper->ReadOccupancy([&](const OccupancyMap& map) {
    *hit = map.CastRay(origin_W, direction_W, max_range_m, unknown_stops);
  });
  // Objects are not in the OctoMap: the ray also stops at the first model point it passes
  // within half a model voxel diagonal of, when that comes before the structure's voxel.
  const Eigen::Vector3d direction = direction_W.normalized();
  const double radius = 0.5 * std::sqrt(3.0) * impl_->config.mapper.objects.model_voxel_size_m;
  double reach = hit->hit ? hit->distance_m : max_range_m;
  *object_hit = 0;
  for (const auto& [id, view] : snapshot->objects) {
    if (!view->model_W ||
        !RayMeetsBox(origin_W, direction, view->min_W.cast<double>().array() - radius,
                     view->max_W.cast<double>().array() + radius, reach)) {
      continue;
    }
    for (const Eigen::Vector3f& point : view->model_W->points) {
      const Eigen::Vector3d offset = point.cast<double>() - origin_W;
      const double along = offset.dot(direction);
      if (along < 0.0 || along >= reach) continue;
      if ((offset - along * direction).squaredNorm() > radius * radius) continue;
      reach = along;
      *object_hit = id;
      hit->hit = true;
      hit->state = VoxelState::kOccupied;
      hit->voxel_center_W = point.cast<double>();
      hit->distance_m = along;
    }
  }
  // The structure's voxels also hold object surfaces seen in keyframes where the object was not
  // segmented (not detected, or only part of it). A structure voxel that an object's model
  // reaches (a model point within the two voxels' half diagonals) is that object's surface.
  if (*object_hit == 0 && hit->hit && hit->state == VoxelState::kOccupied) {
    const double surface_m =
        radius + 0.5 * std::sqrt(3.0) * impl_->config.mapper.occupancy.resolution_m;
    double nearest_sq = surface_m * surface_m;
    const Eigen::Vector3f voxel = hit->voxel_center_W.cast<float>();
    for (const auto& [id, view] : snapshot->objects) {
      if (!view->model_W ||
          !BoxesOverlap(view->min_W, view->max_W, hit->voxel_center_W.array() - surface_m,
                        hit->voxel_center_W.array() + surface_m)) {
        continue;
      }
      for (const Eigen::Vector3f& point : view->model_W->points) {
        const double distance_sq = (point - voxel).cast<double>().squaredNorm();
        if (distance_sq > nearest_sq) continue;
        nearest_sq = distance_sq;
        *object_hit = id;
      }
    }
  }
  return ServiceStatus::Ok();
}

ServiceStatus MapServer::OctomapBytes(
    const std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& region, std::string* bytes,
    std::size_t* leaf_count, std::uint64_t* version) const {
  std::string why;
  if (region && !ValidateBox(region->first, region->second, "region", &why)) {
    return ServiceStatus::Invalid(why);
  }
  return impl_->RunHeavy([&] {
    const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
    *version = impl_->Current()->version;
    impl_->mapper->ReadOccupancy([&](const OccupancyMap& map) {
      *bytes = map.BinaryBytes(region.has_value(), region ? region->first : zero,
                               region ? region->second : zero, leaf_count);
    });
    return ServiceStatus::Ok();
  });
}

ServiceStatus MapServer::OccupiedCenters(std::size_t max_count,
                                         std::vector<Eigen::Vector3d>* centers,
                                         std::uint64_t* version) const {
  if (max_count == 0) return ServiceStatus::Invalid("max_count must be positive");
  *version = impl_->Current()->version;
  impl_->mapper->ReadOccupancy(
      [&](const OccupancyMap& map) { *centers = map.OccupiedVoxelCenters(); });
  ThinEvenly(max_count, centers);
  return ServiceStatus::Ok();
}

void ThinEvenly(std::size_t max_count, std::vector<Eigen::Vector3d>* points) {
  if (max_count == 0 || points->size() <= max_count) return;
  const std::size_t stride = (points->size() + max_count - 1) / max_count;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < points->size(); i += stride) (*points)[kept++] = (*points)[i];
  points->resize(kept);
}

ServiceStatus MapServer::ListKeyframes(KeyframeId first_id, std::size_t max_count,
                                       std::vector<KeyframeSummary>* keyframes,
                                       std::uint64_t* version) const {
  if (first_id < 0) {
    return ServiceStatus::Invalid("first_id " + std::to_string(first_id) + " must be >= 0");
  }
  *version = impl_->Current()->version;
  std::string why;
  if (!impl_->store->ListKeyframes(first_id, max_count, keyframes, &why)) {
    return {StatusCode::kInternal, "keyframes not read: " + why};
  }
  return ServiceStatus::Ok();
}

}  // namespace objmap
