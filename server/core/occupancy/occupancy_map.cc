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
using occupancy_internal::PackKey;
using occupancy_internal::PointToKey;
using occupancy_internal::UnpackKey;
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

// Turns the scan's points into free-space ray ends and occupied endpoint keys, and the key box.
void OccupancyMap::Impl::CollectRays(const ScanW& scan) {
  ray_ends_W.clear();
  occupied_keys.clear();
  const Eigen::Vector3f& origin = scan.origin_W;
  const float margin_m = static_cast<float>(config.object_margin_voxels * config.resolution_m);
  const bool structure_margin =
      config.structure_margin_m > 0.0 || config.structure_margin_per_m2 > 0.0;
  auto structure_margin_of = [this](float range_m) {
    return static_cast<float>(config.structure_margin_m +
                              config.structure_margin_per_m2 * range_m * range_m);
  };
  // Object rays stop short of the object surface so they do not erase the structure it touches,
  // nor, where depth noise put the point behind it, the object's own surface.
  auto object_margin_of = [&](float range_m) {
    return std::max(margin_m, structure_margin_of(range_m));
  };
  for (const Eigen::Vector3f& p : scan.structure_points_W) {
    if (!AllFinite(p)) continue;
    RayEnd ray = ClipRay(origin, p, config.max_range_m);
    VoxelKey key;
    if (ray.in_range && PointToKey(p, config.resolution_m, &key)) {
      occupied_keys.push_back(PackKey(key));
    }
    if (ray.in_range && structure_margin &&
        !StopShort(origin, p, structure_margin_of, &ray.end_W)) {
      continue;
    }
    ray_ends_W.push_back(ray.end_W);
  }
  for (const Eigen::Vector3f& p : scan.object_points_W) {
    if (!AllFinite(p)) continue;
    RayEnd ray = ClipRay(origin, p, config.max_range_m);
    if (ray.in_range && !StopShort(origin, p, object_margin_of, &ray.end_W)) continue;
    ray_ends_W.push_back(ray.end_W);
  }
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
  // Occupied endpoints win over free space seen in the same scan (as OcTree::computeUpdate).
  for (std::uint64_t packed : occupied_keys) grid.Clear(UnpackKey(packed));
  grid.BuildPyramid();
}

void OccupancyMap::Impl::ApplyOccupied() {
  for (std::uint64_t packed : occupied_keys) {
    const VoxelKey k = UnpackKey(packed);
    tree.updateNode(octomap::OcTreeKey(k[0], k[1], k[2]), true, /*lazy_eval=*/false);
  }
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
  m.stats.rays = m.ray_ends_W.size();
  m.stats.occupied_voxels = m.occupied_keys.size();
  m.stats.free_voxels = m.grid.CountSet();
  m.stats.cast_ms = MsSince(start);
  m.scan_prepared = true;
}

void OccupancyMap::ApplyPreparedScan() {
  Impl& m = *impl_;
  if (!m.scan_prepared) return;
  m.scan_prepared = false;
  const Clock::time_point update_start = Clock::now();
  m.tree.ApplyFreeSpace(m.grid);
  m.ApplyOccupied();
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
