// Segmenter: normals -> supporting planes -> grid supervoxels -> weighted adjacency graph ->
// Felzenszwalb-Huttenlocher (Kruskal) cut -> small-segment merge (paper Sec. III-B).
#include "segmentation/segmenter.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <utility>

#include "segmentation/segmentation_internal.h"

namespace objmap {
namespace {

// Used only when the cloud is too sparse to recover its focal length (Kinect-class sensors).
constexpr float kFallbackFocalPx = 525.f;

// Union-find over supervoxels with the segment size (pixels) and internal difference Int(C).
class Components {
 public:
  explicit Components(const std::vector<seg::Supervoxel>& supervoxels)
      : parent_(supervoxels.size()), pixels_(supervoxels.size()), internal_(supervoxels.size()) {
    std::iota(parent_.begin(), parent_.end(), 0);
    for (size_t i = 0; i < supervoxels.size(); ++i) pixels_[i] = supervoxels[i].pixels;
  }
  int Find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void Unite(int a, int b, float weight) {
    if (pixels_[a] < pixels_[b]) std::swap(a, b);
    parent_[b] = a;
    pixels_[a] += pixels_[b];
    internal_[a] = std::max({internal_[a], internal_[b], weight});
  }
  int Pixels(int root) const { return pixels_[root]; }
  float Threshold(int root, float k) const { return internal_[root] + k / pixels_[root]; }

 private:
  std::vector<int> parent_;
  std::vector<int> pixels_;
  std::vector<float> internal_;
};

// Plane pieces connected to nothing big of their plane are object surfaces (a pot's floor lies
// within the inlier distance of the table but is walled off from it by depth edges).
void DropSmallPlanePatches(const SegmenterConfig& config, std::vector<seg::Supervoxel>* supervoxels,
                           std::vector<seg::GraphEdge>* edges) {
  std::vector<seg::Supervoxel>& svs = *supervoxels;
  Components patches(svs);
  for (const seg::GraphEdge& e : *edges) {
    if (svs[e.a].plane < 0 || svs[e.a].plane != svs[e.b].plane) continue;
    const int a = patches.Find(e.a);
    const int b = patches.Find(e.b);
    if (a != b) patches.Unite(a, b, 0.f);
  }
  std::vector<float> area_m2(svs.size(), 0.f);
  for (size_t s = 0; s < svs.size(); ++s) {
    if (svs[s].plane >= 0) area_m2[patches.Find(static_cast<int>(s))] += svs[s].area_m2;
  }
  std::vector<bool> changed(svs.size(), false);
  bool any_changed = false;
  for (size_t s = 0; s < svs.size(); ++s) {
    if (svs[s].plane < 0) continue;
    if (area_m2[patches.Find(static_cast<int>(s))] < config.min_plane_patch_area_m2) {
      svs[s].plane = -1;
      changed[s] = true;
      any_changed = true;
    }
  }
  if (!any_changed) return;
  // Only edges at a supervoxel that left its plane weigh differently now.
  for (seg::GraphEdge& e : *edges) {
    if (changed[e.a] || changed[e.b]) {
      e.weight = seg::EdgeWeight(svs[e.a], svs[e.b], config.convex_tolerance);
    }
  }
}

// Stable sort by weight: ties keep the graph's (a, b) order, which the cut's result depends on.
// Weights are >= 0, so their bit patterns order like the floats: a least-significant-digit radix
// sort on those bits, one byte per pass, is stable and needs no comparisons. Edges inside one
// plane (weight 0, often half of them) are already in place in front.
void SortByWeight(std::vector<seg::GraphEdge>* edges) {
  std::vector<seg::GraphEdge> sorted;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keys;  // (weight bits, edge)
  sorted.reserve(edges->size());
  for (size_t k = 0; k < edges->size(); ++k) {
    const float weight = (*edges)[k].weight;
    if (weight == 0.f) {
      sorted.push_back((*edges)[k]);
      continue;
    }
    std::uint32_t bits = 0;
    std::memcpy(&bits, &weight, sizeof(bits));
    keys.emplace_back(bits, static_cast<std::uint32_t>(k));
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> buffer(keys.size());
  for (int shift = 0; shift < 32; shift += 8) {
    size_t count[257] = {};
    for (const auto& key : keys) ++count[((key.first >> shift) & 0xff) + 1];
    for (int digit = 0; digit < 256; ++digit) count[digit + 1] += count[digit];
    for (const auto& key : keys) buffer[count[(key.first >> shift) & 0xff]++] = key;
    keys.swap(buffer);
  }
  for (const auto& key : keys) sorted.push_back((*edges)[key.second]);
  edges->swap(sorted);
}

// Kruskal over edges sorted by weight: merge when the edge is no heavier than both segments'
// Int(C) + k / |C| (Felzenszwalb & Huttenlocher 2004), then absorb segments under the size floor.
void CutGraph(std::vector<seg::GraphEdge>* edges, const SegmenterConfig& config,
              Components* components) {
  SortByWeight(edges);
  for (const seg::GraphEdge& e : *edges) {
    const int a = components->Find(e.a);
    const int b = components->Find(e.b);
    if (a == b) continue;
    if (e.weight <= std::min(components->Threshold(a, config.kruskal_k_px),
                             components->Threshold(b, config.kruskal_k_px))) {
      components->Unite(a, b, e.weight);
    }
  }
  for (const seg::GraphEdge& e : *edges) {
    const int a = components->Find(e.a);
    const int b = components->Find(e.b);
    if (a == b) continue;
    if (components->Pixels(a) < config.min_segment_px ||
        components->Pixels(b) < config.min_segment_px) {
      components->Unite(a, b, e.weight);
    }
  }
}

// Compact segment ids per pixel; a segment is a supporting plane when most of its pixels are.
SegmentationResult Relabel(const OrganizedCloud& cloud, const std::vector<int>& supervoxel_of_pixel,
                           const std::vector<seg::Supervoxel>& supervoxels,
                           Components* components) {
  SegmentationResult result;
  result.width = cloud.width;
  result.height = cloud.height;
  result.labels.assign(cloud.size(), -1);
  std::vector<int> segment_of_root(supervoxels.size(), -1);
  std::vector<int> segment_of_supervoxel(supervoxels.size(), -1);
  std::vector<int> plane_pixels;
  std::vector<int> all_pixels;
  for (size_t s = 0; s < supervoxels.size(); ++s) {
    const int root = components->Find(static_cast<int>(s));
    if (segment_of_root[root] < 0) {
      segment_of_root[root] = result.num_segments++;
      plane_pixels.push_back(0);
      all_pixels.push_back(0);
    }
    const int id = segment_of_root[root];
    segment_of_supervoxel[s] = id;
    all_pixels[id] += supervoxels[s].pixels;
    if (supervoxels[s].plane >= 0) plane_pixels[id] += supervoxels[s].pixels;
  }
  for (size_t i = 0; i < cloud.size(); ++i) {
    const int s = supervoxel_of_pixel[i];
    if (s >= 0) result.labels[i] = segment_of_supervoxel[s];
  }
  result.segment_is_plane.resize(result.num_segments);
  for (int id = 0; id < result.num_segments; ++id) {
    result.segment_is_plane[id] = 2 * plane_pixels[id] > all_pixels[id];
  }
  return result;
}

// Fallback for an unusable config: every valid point in one non-plane segment.
SegmentationResult SingleSegment(const OrganizedCloud& cloud) {
  SegmentationResult result;
  result.width = cloud.width;
  result.height = cloud.height;
  result.labels.assign(cloud.size(), -1);
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.IsValid(static_cast<int>(i))) result.labels[i] = 0;
  }
  result.num_segments = 1;
  result.segment_is_plane = {false};
  return result;
}

}  // namespace

bool SegmenterConfig::IsValid(std::string* why) const {
  auto fail = [why](const char* field) {
    if (why) *why = std::string("SegmenterConfig.") + field + " is out of range";
    return false;
  };
  if (!(depth_jump_ratio > 0.f)) return fail("depth_jump_ratio");
  if (normal_step_px < 1 || normal_step_px > 32) return fail("normal_step_px");
  if (max_planes < 0 || max_planes > 100) return fail("max_planes");
  if (!(min_plane_area_m2 > 0.f)) return fail("min_plane_area_m2");
  if (!(min_plane_patch_area_m2 >= 0.f)) return fail("min_plane_patch_area_m2");
  if (!(plane_distance_m > 0.f)) return fail("plane_distance_m");
  if (!(plane_normal_angle_deg > 0.f && plane_normal_angle_deg < 90.f)) {
    return fail("plane_normal_angle_deg");
  }
  if (plane_iterations < 1) return fail("plane_iterations");
  if (cell_px < 1 || cell_px > 64) return fail("cell_px");
  if (!(kruskal_k_px >= 0.f)) return fail("kruskal_k_px");
  if (!(convex_tolerance >= 0.f)) return fail("convex_tolerance");
  if (min_segment_px < 0) return fail("min_segment_px");
  return true;
}

Segmenter::Segmenter(const SegmenterConfig& config) : config_(config) {}

SegmentationResult Segmenter::Segment(const OrganizedCloud& cloud_C) const {
  const size_t n = static_cast<size_t>(std::max(0, cloud_C.width)) * std::max(0, cloud_C.height);
  if (n == 0 || cloud_C.points_C.size() != n) {
    SegmentationResult empty;
    empty.labels.assign(cloud_C.points_C.size(), -1);
    return empty;
  }
  if (!config_.IsValid(nullptr)) return SingleSegment(cloud_C);
  const std::vector<Eigen::Vector3f> normals =
      seg::ComputeNormals(cloud_C, config_.normal_step_px, config_.depth_jump_ratio);
  const float focal_px = seg::EstimateFocalPx(cloud_C, kFallbackFocalPx);
  std::vector<std::int8_t> plane_of_pixel;
  seg::DetectSupportingPlanes(cloud_C, normals, config_, focal_px, &plane_of_pixel);
  std::vector<int> supervoxel_of_pixel;
  std::vector<seg::Supervoxel> supervoxels;
  seg::BuildSupervoxels(cloud_C, normals, plane_of_pixel, config_, focal_px, &supervoxel_of_pixel,
                        &supervoxels);
  std::vector<seg::GraphEdge> edges =
      seg::BuildAdjacencyGraph(cloud_C, supervoxel_of_pixel, supervoxels, config_);
  DropSmallPlanePatches(config_, &supervoxels, &edges);
  Components components(supervoxels);
  CutGraph(&edges, config_, &components);
  return Relabel(cloud_C, supervoxel_of_pixel, supervoxels, &components);
}

}  // namespace objmap
