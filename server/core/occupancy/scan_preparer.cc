#include "occupancy/scan_preparer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace objmap {
namespace {

using occupancy_internal::PointToKey;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Where the free-space ray of one point ends, following OcTree::computeUpdate: rays longer than
// max_range stop at max_range (float arithmetic as OctoMap, for identical voxel sets).
struct RayEnd {
  Eigen::Vector3f end_W;
  bool in_range = false;  // true when the point itself is within max_range
};

RayEnd ClipRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& point, double max_range_m) {
  const Eigen::Vector3f d = point - origin;
  const double norm = std::sqrt(static_cast<double>(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
  if (max_range_m < 0.0 || norm <= max_range_m) return {point, true};
  const Eigen::Vector3f direction = d / static_cast<float>(norm);
  return {origin + direction * static_cast<float>(max_range_m), false};
}

bool AllFinite(const Eigen::Vector3f& p) { return p.allFinite(); }

bool HasDepth(const Eigen::Vector3f& p_C) { return p_C.allFinite() && p_C.z() > 0.f; }

// The projective integration needs each point on its pixel's ray (as BackProject makes them);
// the tolerance allows for float rounding and is well below the carver's margin.
bool PointsLieOnPixelRays(const DepthScanW& scan) {
  constexpr float kTolerancePx = 0.01f;
  if (scan.width <= 0 || scan.height <= 0 ||
      scan.points_C.size() != static_cast<std::size_t>(scan.width) * scan.height ||
      !(std::isfinite(scan.fx) && scan.fx > 0.f && std::isfinite(scan.fy) && scan.fy > 0.f &&
        std::isfinite(scan.cx) && std::isfinite(scan.cy)) ||
      !scan.T_W_C.matrix().allFinite()) {
    return false;
  }
  for (int v = 0; v < scan.height; ++v) {
    for (int u = 0; u < scan.width; ++u) {
      const Eigen::Vector3f& p = scan.points_C[static_cast<std::size_t>(v) * scan.width + u];
      if (!HasDepth(p)) continue;
      if (std::fabs(scan.fx * p.x() / p.z() + scan.cx - static_cast<float>(u)) > kTolerancePx ||
          std::fabs(scan.fy * p.y() / p.z() + scan.cy - static_cast<float>(v)) > kTolerancePx) {
        return false;
      }
    }
  }
  return true;
}

// The free-space end of a ray to `point` that stops margin_of(range) short of it; false (no
// ray) when the point is no farther than that from the origin.
template <typename MarginOf>
bool StopShort(const Eigen::Vector3f& origin, const Eigen::Vector3f& point, MarginOf margin_of,
               Eigen::Vector3f* end_W) {
  const Eigen::Vector3f d = point - origin;
  const float length = d.norm();
  const float margin_m = margin_of(length);
  if (length <= margin_m) return false;
  *end_W = point - d * (margin_m / length);
  return true;
}

}  // namespace

ScanW ToScanW(const DepthScanW& scan) {
  ScanW points;
  points.origin_W = scan.T_W_C.translation();
  const bool has_mask = scan.object_mask.size() == scan.points_C.size();
  for (std::size_t i = 0; i < scan.points_C.size(); ++i) {
    const Eigen::Vector3f& p_C = scan.points_C[i];
    if (!HasDepth(p_C)) continue;
    (has_mask && scan.object_mask[i] != 0 ? points.object_points_W : points.structure_points_W)
        .push_back(scan.T_W_C * p_C);
  }
  return points;
}

namespace occupancy_internal {

ScanPreparer::PointRay ScanPreparer::RayOf(const Eigen::Vector3f& origin,
                                           const Eigen::Vector3f& point_W, bool is_object) const {
  PointRay ray;
  if (!AllFinite(point_W)) return ray;
  auto structure_margin_of = [this](float range_m) {
    return static_cast<float>(config_.structure_margin_m +
                              config_.structure_margin_per_m2 * range_m * range_m);
  };
  RayEnd end = ClipRay(origin, point_W, config_.max_range_m);
  ray.free_end_W = end.end_W;
  ray.carves = true;
  if (!is_object) {
    ray.marks_occupied =
        end.in_range && PointToKey(point_W, config_.resolution_m, &ray.occupied_key);
    const bool structure_margin =
        config_.structure_margin_m > 0.0 || config_.structure_margin_per_m2 > 0.0;
    if (end.in_range && structure_margin) {
      ray.carves = StopShort(origin, point_W, structure_margin_of, &ray.free_end_W);
    }
    return ray;
  }
  // Object rays stop short of the object surface so they do not erase the structure it touches,
  // nor, where depth noise put the point behind it, the object's own surface.
  const float margin_m = static_cast<float>(config_.object_margin_voxels * config_.resolution_m);
  auto object_margin_of = [&](float range_m) {
    return std::max(margin_m, structure_margin_of(range_m));
  };
  if (end.in_range) ray.carves = StopShort(origin, point_W, object_margin_of, &ray.free_end_W);
  return ray;
}

// Turns the scan's points into free-space ray ends and occupied endpoint keys.
void ScanPreparer::CollectRays(const ScanW& scan) {
  ray_ends_W_.clear();
  occupied_keys_.clear();
  auto collect = [this, &scan](const std::vector<Eigen::Vector3f>& points, bool is_object) {
    for (const Eigen::Vector3f& p : points) {
      const PointRay ray = RayOf(scan.origin_W, p, is_object);
      if (ray.marks_occupied) occupied_keys_.push_back(MortonCode(ray.occupied_key));
      if (ray.carves) ray_ends_W_.push_back(ray.free_end_W);
    }
  };
  collect(scan.structure_points_W, false);
  collect(scan.object_points_W, true);
  if (config_.one_ray_per_end_voxel) KeepOneRayPerEndVoxel();
  SortOccupied();
}

// Rays to points in the same end voxel cross nearly the same voxels; keep the first of each.
void ScanPreparer::KeepOneRayPerEndVoxel() {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(ray_ends_W_.size());
  for (std::size_t i = 0; i < ray_ends_W_.size(); ++i) {
    VoxelKey key;
    if (PointToKey(ray_ends_W_[i], config_.resolution_m, &key)) {
      keyed.emplace_back(PackKey(key), static_cast<std::uint32_t>(i));
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<Eigen::Vector3f> kept;
  kept.reserve(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first)
      kept.push_back(ray_ends_W_[keyed[i].second]);
  }
  ray_ends_W_.swap(kept);
}

void ScanPreparer::CastRays(const Eigen::Vector3f& origin, const VoxelKey& origin_key) {
  min_key_ = max_key_ = origin_key;
  std::size_t kept = 0;
  for (const Eigen::Vector3f& end : ray_ends_W_) {
    VoxelKey key;
    if (!PointToKey(end, config_.resolution_m, &key)) continue;
    for (int i = 0; i < 3; ++i) {
      min_key_[i] = std::min(min_key_[i], key[i]);
      max_key_[i] = std::max(max_key_[i], key[i]);
    }
    ray_ends_W_[kept++] = end;
  }
  ray_ends_W_.resize(kept);
  grid_.Reset(min_key_, max_key_);
  for (const Eigen::Vector3f& end : ray_ends_W_) grid_.AddRay(origin, end);
}

bool ScanPreparer::CollectPixelRays(const DepthScanW& scan) {
  VoxelKey origin_key;
  if (!PointsLieOnPixelRays(scan) ||
      !PointToKey(scan.T_W_C.translation(), config_.resolution_m, &origin_key)) {
    return false;
  }
  occupied_keys_.clear();
  PinholeCamera camera;
  camera.T_W_C = scan.T_W_C;
  camera.width = scan.width;
  camera.height = scan.height;
  camera.fx = scan.fx;
  camera.fy = scan.fy;
  camera.cx = scan.cx;
  camera.cy = scan.cy;
  carver_.Reset(camera);
  const Eigen::Vector3f origin = scan.T_W_C.translation();
  const bool has_mask = scan.object_mask.size() == scan.points_C.size();
  for (std::size_t i = 0; i < scan.points_C.size(); ++i) {
    const Eigen::Vector3f& p_C = scan.points_C[i];
    if (!HasDepth(p_C)) continue;
    const PointRay ray = RayOf(origin, scan.T_W_C * p_C, has_mask && scan.object_mask[i] != 0);
    if (ray.marks_occupied) occupied_keys_.push_back(MortonCode(ray.occupied_key));
    if (ray.carves) carver_.SetRay(static_cast<int>(i), ray.free_end_W);
  }
  SortOccupied();
  return true;
}

void ScanPreparer::SortOccupied() {
  std::sort(occupied_keys_.begin(), occupied_keys_.end());
  occupied_keys_.erase(std::unique(occupied_keys_.begin(), occupied_keys_.end()),
                       occupied_keys_.end());
}

void ScanPreparer::Prepare(const ScanW& scan) { PrepareRayByRay(scan, nullptr); }

void ScanPreparer::PrepareRayByRay(const ScanW& scan, const FreeSpaceGrid* region) {
  stats_ = IntegrationStats{};
  ready_ = false;
  applied_ = false;
  VoxelKey origin_key;
  // Like OctoMap, an origin outside the key range casts no rays and marks nothing.
  if (!AllFinite(scan.origin_W) || !PointToKey(scan.origin_W, config_.resolution_m, &origin_key)) {
    return;
  }
  const Clock::time_point start = Clock::now();
  CollectRays(scan);
  CastRays(scan.origin_W, origin_key);
  if (region != nullptr) DropOutside(*region);
  Finish(start, ray_ends_W_.size());
}

void ScanPreparer::Prepare(const DepthScanW& scan, const FreeSpaceGrid* region) {
  if (!CollectPixelRays(scan)) {
    PrepareRayByRay(ToScanW(scan), region);
    return;
  }
  stats_ = IntegrationStats{};
  ready_ = false;
  applied_ = false;
  const Clock::time_point start = Clock::now();
  carver_.KeyBox(&min_key_, &max_key_);
  grid_.Reset(min_key_, max_key_);
  const CarvingStats carving = carver_.Carve(&grid_, region, threads_);
  stats_.projective = true;
  stats_.blocks_decided = carving.blocks_decided;
  stats_.voxels_tested = carving.voxels_tested;
  if (region != nullptr) DropOutside(*region);
  Finish(start, carver_.rays());
}

void ScanPreparer::MarkReach(const DepthScanW& scan, int block_log2, FreeSpaceGrid* region) {
  const int block = 1 << block_log2;
  auto mark_occupied = [&] {
    for (std::uint64_t code : occupied_keys_) {
      VoxelKey key = KeyOfMortonCode(code);
      for (std::uint16_t& k : key) k = static_cast<std::uint16_t>(k & ~(block - 1));
      region->MarkBlock(key, block_log2);
    }
  };
  if (CollectPixelRays(scan)) {
    carver_.MarkReachedBlocks(block_log2, region);
    mark_occupied();
    return;
  }
  // Points off their pixel rays: the rays themselves, voxel by voxel.
  const ScanW points = ToScanW(scan);
  VoxelKey origin_key;
  if (!AllFinite(points.origin_W) ||
      !PointToKey(points.origin_W, config_.resolution_m, &origin_key)) {
    return;
  }
  CollectRays(points);
  for (const Eigen::Vector3f& end : ray_ends_W_) region->AddRay(points.origin_W, end);
  mark_occupied();
}

void ScanPreparer::DropOutside(const FreeSpaceGrid& region) {
  occupied_keys_.erase(
      std::remove_if(occupied_keys_.begin(), occupied_keys_.end(),
                     [&region](std::uint64_t code) { return !region.Test(KeyOfMortonCode(code)); }),
      occupied_keys_.end());
  grid_.KeepOnly(region);
}

void ScanPreparer::Finish(Clock::time_point start, std::size_t rays) {
  // Occupied endpoints win over free space seen in the same scan (as OcTree::computeUpdate).
  for (std::uint64_t code : occupied_keys_) grid_.Clear(KeyOfMortonCode(code));
  grid_.BuildPyramid();
  stats_.rays = rays;
  stats_.occupied_voxels = occupied_keys_.size();
  stats_.free_voxels = grid_.CountSet();
  stats_.cast_ms = MsSince(start);
  ready_ = true;
}

}  // namespace occupancy_internal
}  // namespace objmap
