#include "occupancy/occupancy_map.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

#include "occupancy/batch_octree.h"
#include "occupancy/free_space_grid.h"
#include "occupancy/occupancy_map_impl.h"

namespace objmap {
namespace {

using occupancy_internal::BatchOcTree;
using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool IsProbability(double p) { return std::isfinite(p) && p > 0.0 && p < 1.0; }

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
  if (threads_per_scan < 1 || threads_per_scan > 64) {
    return fail("threads_per_scan must lie in [1, 64]");
  }
  if (!(structure_margin_m >= 0.0) || !(structure_margin_per_m2 >= 0.0)) {
    return fail("structure_margin_m and structure_margin_per_m2 must be >= 0");
  }
  return true;
}

OccupancyMap::OccupancyMap(const OccupancyConfig& config) : impl_(std::make_unique<Impl>(config)) {}
OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::Impl::Apply(occupancy_internal::ScanPreparer* prepared) {
  stats = prepared->stats();
  if (!prepared->ready()) return;
  const Clock::time_point update_start = Clock::now();
  tree.ApplyScan(prepared->free_space(), prepared->occupied());
  stats.tree_update_ms = MsSince(update_start);
  prepared->MarkApplied();
}

void OccupancyMap::Integrate(const ScanW& scan) {
  PrepareScan(scan);
  ApplyPreparedScan();
}

void OccupancyMap::PrepareScan(const ScanW& scan) {
  impl_->preparer.Prepare(scan);
  impl_->stats = impl_->preparer.stats();
}

void OccupancyMap::Integrate(const DepthScanW& scan) {
  PrepareScan(scan);
  ApplyPreparedScan();
}

void OccupancyMap::PrepareScan(const DepthScanW& scan) {
  impl_->preparer.Prepare(scan);
  impl_->stats = impl_->preparer.stats();
}

void OccupancyMap::ApplyPreparedScan() { impl_->Apply(&impl_->preparer); }

void OccupancyMap::ApplyScanPreparedBy(const OccupancyMap& source) {
  const occupancy_internal::ScanPreparer& prepared = source.impl_->preparer;
  impl_->stats = prepared.stats();
  if (!prepared.holds_scan()) return;
  const Clock::time_point update_start = Clock::now();
  impl_->tree.ApplyScan(prepared.free_space(), prepared.occupied());
  impl_->stats.tree_update_ms = MsSince(update_start);
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
  // Read aside, once: readBinary takes the file's resolution, and a refused file must leave the
  // map as it was. The aside tree gets this map's clamping, which turns the file's occupied and
  // free bits into log-odds; an accepted file's nodes then change places with the map's.
  octomap::OcTree read(impl_->config.resolution_m);
  read.setClampingThresMin(impl_->tree.getClampingThresMin());
  read.setClampingThresMax(impl_->tree.getClampingThresMax());
  read.setOccupancyThres(impl_->tree.getOccupancyThres());
  read.setProbHit(impl_->tree.getProbHit());
  read.setProbMiss(impl_->tree.getProbMiss());
  std::istringstream stream(bytes);
  if (!read.readBinary(stream)) {
    *why = "not an OctoMap binary (.bt) file";
    return false;
  }
  if (std::abs(read.getResolution() - impl_->config.resolution_m) > 1e-9) {
    *why = "the OctoMap's resolution is " + std::to_string(read.getResolution()) +
           " m, this map's " + std::to_string(impl_->config.resolution_m) + " m";
    return false;
  }
  impl_->tree.clear();  // also marks the cached bounds stale
  impl_->tree.swapContent(read);
  return true;
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

std::size_t OccupancyMap::MemoryBytes() const { return impl_->tree.memoryUsage(); }

const OccupancyConfig& OccupancyMap::config() const { return impl_->config; }

namespace {

// The resolution in the header of an OctoMap binary file: "id OcTree", "size N" (nodes), "res R"
// (metres), then "data". False when a line is missing or malformed (OctoMap itself reads a
// header without "size" as an empty tree).
bool ReadOctomapResolution(const std::string& bytes, double* resolution_m) {
  std::istringstream header(bytes.substr(0, 1024));
  std::string line;
  bool id = false, size = false, resolution = false;
  while (std::getline(header, line)) {
    try {
      if (line == "id OcTree") id = true;
      if (line.rfind("size ", 0) == 0) {
        (void)std::stoul(line.substr(5));
        size = true;
      }
      if (line.rfind("res ", 0) == 0) {
        *resolution_m = std::stod(line.substr(4));
        resolution = *resolution_m > 0.0 && *resolution_m < 10.0;
      }
    } catch (const std::exception&) {
      return false;
    }
    if (line == "data") return id && size && resolution;
  }
  return false;
}

}  // namespace

std::unique_ptr<OccupancyMap> ReadOctomapFile(const std::string& path, OccupancyConfig config,
                                              std::string* why) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    *why = path + ": cannot open";
    return nullptr;
  }
  std::ostringstream content;
  content << file.rdbuf();
  const std::string bytes = content.str();
  if (!ReadOctomapResolution(bytes, &config.resolution_m)) {
    *why = path + ": not an OctoMap binary file (its header needs id OcTree, size, res, data)";
    return nullptr;
  }
  auto map = std::make_unique<OccupancyMap>(config);
  if (!map->ReadBinary(bytes, why)) {
    *why = path + ": " + *why;
    return nullptr;
  }
  return map;
}

}  // namespace objmap
