#include "occupancy/occupancy_map.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <utility>

#include "occupancy/batch_octree.h"
#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map_impl.h"

namespace objmap {
namespace {

using occupancy_internal::BatchOcTree;
using occupancy_internal::KeyOfMortonCode;
using occupancy_internal::MortonCode;
using occupancy_internal::PackKey;
using occupancy_internal::PointToKey;
using occupancy_internal::VoxelKey;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool IsProbability(double p) { return std::isfinite(p) && p > 0.0 && p < 1.0; }

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

bool OccupancyConfig::IsValid(std::string* why) const {
  auto fail = [why](const char* message) {
    if (why != nullptr) *why = message;
    return false;
  };
  if (!(std::isfinite(resolution_m) && resolution_m > 0.0)) {
    return fail("resolution_m must be finite and > 0");
  }
  if (std::isnan(max_range_m) || max_range_m == 0.0) {
    return fail("max_range_m must be > 0 (or negative for no limit)");
  }
  if (!IsProbability(probability_hit) || probability_hit <= 0.5) {
    return fail("probability_hit must lie in (0.5, 1)");
  }
  if (!IsProbability(probability_miss) || probability_miss >= 0.5) {
    return fail("probability_miss must lie in (0, 0.5)");
  }
  if (!IsProbability(clamping_min) || !IsProbability(clamping_max) ||
      clamping_min >= clamping_max) {
    return fail("clamping_min/clamping_max must lie in (0, 1) with clamping_min < clamping_max");
  }
  if (object_margin_voxels < 0) return fail("object_margin_voxels must be >= 0");
  if (!(structure_margin_m >= 0.0) || !(structure_margin_per_m2 >= 0.0)) {
    return fail("structure_margin_m and structure_margin_per_m2 must be >= 0");
  }
  return true;
}

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

OccupancyMap::Impl::PointRay OccupancyMap::Impl::RayOf(const Eigen::Vector3f& origin,
                                                       const Eigen::Vector3f& point_W,
                                                       bool is_object) const {
  PointRay ray;
  if (!AllFinite(point_W)) return ray;
  auto structure_margin_of = [this](float range_m) {
    return static_cast<float>(config.structure_margin_m +
                              config.structure_margin_per_m2 * range_m * range_m);
  };
  RayEnd end = ClipRay(origin, point_W, config.max_range_m);
  ray.free_end_W = end.end_W;
  ray.carves = true;
  if (!is_object) {
    ray.marks_occupied =
        end.in_range && PointToKey(point_W, config.resolution_m, &ray.occupied_key);
    const bool structure_margin =
        config.structure_margin_m > 0.0 || config.structure_margin_per_m2 > 0.0;
    if (end.in_range && structure_margin) {
      ray.carves = StopShort(origin, point_W, structure_margin_of, &ray.free_end_W);
    }
    return ray;
  }
  // Object rays stop short of the object surface so they do not erase the structure it touches,
  // nor, where depth noise put the point behind it, the object's own surface.
  const float margin_m = static_cast<float>(config.object_margin_voxels * config.resolution_m);
  auto object_margin_of = [&](float range_m) {
    return std::max(margin_m, structure_margin_of(range_m));
  };
  if (end.in_range) ray.carves = StopShort(origin, point_W, object_margin_of, &ray.free_end_W);
  return ray;
}

// Turns the scan's points into free-space ray ends and occupied endpoint keys.
void OccupancyMap::Impl::CollectRays(const ScanW& scan) {
  ray_ends_W.clear();
  occupied_keys.clear();
  auto collect = [this, &scan](const std::vector<Eigen::Vector3f>& points, bool is_object) {
    for (const Eigen::Vector3f& p : points) {
      const PointRay ray = RayOf(scan.origin_W, p, is_object);
      if (ray.marks_occupied) occupied_keys.push_back(MortonCode(ray.occupied_key));
      if (ray.carves) ray_ends_W.push_back(ray.free_end_W);
    }
  };
  collect(scan.structure_points_W, false);
  collect(scan.object_points_W, true);
  if (config.one_ray_per_end_voxel) KeepOneRayPerEndVoxel();
  std::sort(occupied_keys.begin(), occupied_keys.end());
  occupied_keys.erase(std::unique(occupied_keys.begin(), occupied_keys.end()), occupied_keys.end());
}

// Rays to points in the same end voxel cross nearly the same voxels; keep the first of each.
void OccupancyMap::Impl::KeepOneRayPerEndVoxel() {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(ray_ends_W.size());
  for (std::size_t i = 0; i < ray_ends_W.size(); ++i) {
    VoxelKey key;
    if (PointToKey(ray_ends_W[i], config.resolution_m, &key)) {
      keyed.emplace_back(PackKey(key), static_cast<std::uint32_t>(i));
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<Eigen::Vector3f> kept;
  kept.reserve(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) kept.push_back(ray_ends_W[keyed[i].second]);
  }
  ray_ends_W.swap(kept);
}

void OccupancyMap::Impl::CastRays(const Eigen::Vector3f& origin, const VoxelKey& origin_key) {
  min_key = max_key = origin_key;
  std::size_t kept = 0;
  for (const Eigen::Vector3f& end : ray_ends_W) {
    VoxelKey key;
    if (!PointToKey(end, config.resolution_m, &key)) continue;
    for (int i = 0; i < 3; ++i) {
      min_key[i] = std::min(min_key[i], key[i]);
      max_key[i] = std::max(max_key[i], key[i]);
    }
    ray_ends_W[kept++] = end;
  }
  ray_ends_W.resize(kept);
  grid.Reset(min_key, max_key);
  for (const Eigen::Vector3f& end : ray_ends_W) grid.AddRay(origin, end);
}

void OccupancyMap::Impl::CarveDepthScan(const DepthScanW& scan) {
  occupied_keys.clear();
  occupancy_internal::PinholeCamera camera;
  camera.T_W_C = scan.T_W_C;
  camera.width = scan.width;
  camera.height = scan.height;
  camera.fx = scan.fx;
  camera.fy = scan.fy;
  camera.cx = scan.cx;
  camera.cy = scan.cy;
  carver.Reset(camera);
  const Eigen::Vector3f origin = scan.T_W_C.translation();
  const bool has_mask = scan.object_mask.size() == scan.points_C.size();
  for (std::size_t i = 0; i < scan.points_C.size(); ++i) {
    const Eigen::Vector3f& p_C = scan.points_C[i];
    if (!HasDepth(p_C)) continue;
    const PointRay ray = RayOf(origin, scan.T_W_C * p_C, has_mask && scan.object_mask[i] != 0);
    if (ray.marks_occupied) occupied_keys.push_back(MortonCode(ray.occupied_key));
    if (ray.carves) carver.SetRay(static_cast<int>(i), ray.free_end_W);
  }
  std::sort(occupied_keys.begin(), occupied_keys.end());
  occupied_keys.erase(std::unique(occupied_keys.begin(), occupied_keys.end()), occupied_keys.end());
  carver.KeyBox(&min_key, &max_key);
  grid.Reset(min_key, max_key);
}

void OccupancyMap::Impl::FinishPreparedScan(Clock::time_point start, std::size_t rays) {
  // Occupied endpoints win over free space seen in the same scan (as OcTree::computeUpdate).
  for (std::uint64_t code : occupied_keys) grid.Clear(KeyOfMortonCode(code));
  grid.BuildPyramid();
  stats.rays = rays;
  stats.occupied_voxels = occupied_keys.size();
  stats.free_voxels = grid.CountSet();
  stats.cast_ms = MsSince(start);
  scan_prepared = true;
}

OccupancyMap::OccupancyMap(const OccupancyConfig& config) : impl_(std::make_unique<Impl>(config)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::Integrate(const ScanW& scan) {
  PrepareScan(scan);
  ApplyPreparedScan();
}

void OccupancyMap::PrepareScan(const ScanW& scan) {
  Impl& m = *impl_;
  m.stats = IntegrationStats{};
  m.scan_prepared = false;
  VoxelKey origin_key;
  // Like OctoMap, an origin outside the key range casts no rays and marks nothing.
  if (!AllFinite(scan.origin_W) || !PointToKey(scan.origin_W, m.config.resolution_m, &origin_key)) {
    return;
  }
  const Clock::time_point start = Clock::now();
  m.CollectRays(scan);
  m.CastRays(scan.origin_W, origin_key);
  m.FinishPreparedScan(start, m.ray_ends_W.size());
}

void OccupancyMap::Integrate(const DepthScanW& scan) {
  PrepareScan(scan);
  ApplyPreparedScan();
}

void OccupancyMap::PrepareScan(const DepthScanW& scan) {
  if (!PointsLieOnPixelRays(scan)) {
    PrepareScan(ToScanW(scan));
    return;
  }
  Impl& m = *impl_;
  m.stats = IntegrationStats{};
  m.scan_prepared = false;
  VoxelKey origin_key;
  if (!PointToKey(scan.T_W_C.translation(), m.config.resolution_m, &origin_key)) return;
  const Clock::time_point start = Clock::now();
  m.CarveDepthScan(scan);
  const occupancy_internal::CarvingStats carving = m.carver.Carve(&m.grid);
  m.stats.projective = true;
  m.stats.blocks_decided = carving.blocks_decided;
  m.stats.voxels_tested = carving.voxels_tested;
  m.FinishPreparedScan(start, m.carver.rays());
}

void OccupancyMap::ApplyPreparedScan() {
  Impl& m = *impl_;
  if (!m.scan_prepared) return;
  m.scan_prepared = false;
  const Clock::time_point update_start = Clock::now();
  m.tree.ApplyScan(m.grid, m.occupied_keys);
  m.stats.tree_update_ms = MsSince(update_start);
}

const IntegrationStats& OccupancyMap::last_stats() const { return impl_->stats; }

namespace {

// WriteState() bytes: "objmap occupancy state 1 <resolution> <bytes> <checksum>\n" and then
// OctoMap's node data. The length and checksum are checked before OctoMap reads the data,
// because its reader trusts the stream (a truncated one would make it read garbage).
constexpr char kStateFormat[] = "objmap occupancy state 1";

// FNV-1a, 64 bit.
std::uint64_t Checksum(const char* data, std::size_t size) {
  std::uint64_t hash = 14695981039346656037ull;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 1099511628211ull;
  }
  return hash;
}

std::string StateHeader(double resolution_m, std::size_t bytes, std::uint64_t checksum) {
  char header[128];
  std::snprintf(header, sizeof(header), "%s %.17g %zu %016llx\n", kStateFormat, resolution_m,
                bytes, static_cast<unsigned long long>(checksum));
  return header;
}

}  // namespace

std::string OccupancyMap::WriteState() const {
  std::ostringstream data;
  if (impl_->tree.size() > 0) impl_->tree.writeData(data);
  const std::string nodes = data.str();
  return StateHeader(impl_->config.resolution_m, nodes.size(),
                     Checksum(nodes.data(), nodes.size())) +
         nodes;
}

bool OccupancyMap::ReadState(const std::string& bytes, std::string* why) {
  const std::size_t line_end = bytes.find('\n');
  const std::string header = bytes.substr(0, line_end == std::string::npos ? 0 : line_end + 1);
  const std::size_t nodes_size = bytes.size() - header.size();
  const char* nodes = bytes.data() + header.size();
  const std::string expected =
      StateHeader(impl_->config.resolution_m, nodes_size, Checksum(nodes, nodes_size));
  if (header != expected) {
    *why = "occupancy state: header '" + header.substr(0, 96) + "' does not match '" +
           expected.substr(0, expected.size() - 1) +
           "' (another resolution, or truncated or corrupt data)";
    return false;
  }
  impl_->tree.clear();
  if (nodes_size == 0) return true;  // an empty map
  std::istringstream stream(std::string(nodes, nodes_size));
  impl_->tree.readData(stream);
  return true;
}

VoxelState OccupancyMap::Query(const Eigen::Vector3d& point_W) const {
  octomap::OcTreeKey key;
  if (!point_W.allFinite() ||
      !impl_->tree.coordToKeyChecked(
          octomap::point3d(static_cast<float>(point_W.x()), static_cast<float>(point_W.y()),
                           static_cast<float>(point_W.z())),
          key)) {
    return VoxelState::kUnknown;
  }
  const octomap::OcTreeNode* node = impl_->tree.search(key);
  if (node == nullptr) return VoxelState::kUnknown;
  return impl_->tree.isNodeOccupied(node) ? VoxelState::kOccupied : VoxelState::kFree;
}

OccupancyCounts OccupancyMap::Counts() const {
  OccupancyCounts counts;
  const BatchOcTree& tree = impl_->tree;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const std::size_t leaves = std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
    (tree.isNodeOccupied(*it) ? counts.occupied : counts.free) += leaves;
  }
  return counts;
}

bool OccupancyMap::WriteBinary(const std::string& path, std::string* why) const {
  if (impl_->tree.writeBinaryConst(path)) return true;
  if (why != nullptr) *why = "could not write OctoMap binary file " + path;
  return false;
}

bool OccupancyMap::ReadBinary(const std::string& bytes, std::string* why) {
  // Read aside first: readBinary takes the file's resolution, and a refused file must leave the
  // map as it was.
  octomap::OcTree probe(impl_->config.resolution_m);
  std::istringstream probe_stream(bytes);
  if (!probe.readBinary(probe_stream)) {
    *why = "not an OctoMap binary (.bt) file";
    return false;
  }
  if (std::abs(probe.getResolution() - impl_->config.resolution_m) > 1e-9) {
    *why = "the OctoMap's resolution is " + std::to_string(probe.getResolution()) +
           " m, this map's " + std::to_string(impl_->config.resolution_m) + " m";
    return false;
  }
  std::istringstream stream(bytes);
  impl_->tree.clear();
  return impl_->tree.readBinary(stream);
}

std::vector<Eigen::Vector3d> OccupancyMap::OccupiedVoxelCenters() const {
  std::vector<Eigen::Vector3d> centers;
  const double leaf = impl_->config.resolution_m;
  for (auto it = impl_->tree.begin_leafs(), end = impl_->tree.end_leafs(); it != end; ++it) {
    if (!impl_->tree.isNodeOccupied(*it)) continue;
    const int per_side = static_cast<int>(std::lround(it.getSize() / leaf));
    const Eigen::Vector3d corner = Eigen::Vector3d(it.getX(), it.getY(), it.getZ()) -
                                   Eigen::Vector3d::Constant(it.getSize() / 2);
    for (int x = 0; x < per_side; ++x) {
      for (int y = 0; y < per_side; ++y) {
        for (int z = 0; z < per_side; ++z) {
          centers.push_back(corner + leaf * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5));
        }
      }
    }
  }
  return centers;
}

void OccupancyMap::Clear() { impl_->tree.clear(); }

const OccupancyConfig& OccupancyMap::config() const { return impl_->config; }

}  // namespace objmap
