// The segmentation as it was before its fast paths: straightforward whole-image passes, one
// function per step. Tests compare the fast Segmenter (and its steps) against it.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>

#include "segmentation/reference_segmentation.h"

namespace objmap::reference {

using seg::DepthContinuous;
using seg::EdgeWeight;
using seg::GraphEdge;
using seg::PixelAreaM2;
using seg::Supervoxel;

// Per-pixel normals and the focal length, straight from the organized grid.

namespace {

// The neighbour `du, dv` away when it is valid and on the same surface, else null.
const Eigen::Vector3f* ContinuousNeighbour(const OrganizedCloud& cloud, int u, int v, int du,
                                           int dv, float jump_ratio, int step_px) {
  const int u2 = u + du;
  const int v2 = v + dv;
  if (u2 < 0 || v2 < 0 || u2 >= cloud.width || v2 >= cloud.height) return nullptr;
  const int i = v * cloud.width + u;
  const int j = v2 * cloud.width + u2;
  if (!cloud.IsValid(j)) return nullptr;
  if (!DepthContinuous(cloud.points_C[i].z(), cloud.points_C[j].z(), jump_ratio, step_px)) {
    return nullptr;
  }
  return &cloud.points_C[j];
}

Eigen::Vector3f PixelNormal(const OrganizedCloud& cloud, int u, int v, int s, float jump_ratio) {
  const Eigen::Vector3f nan3 = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  const Eigen::Vector3f& p = cloud.points_C[v * cloud.width + u];
  const Eigen::Vector3f* right = ContinuousNeighbour(cloud, u, v, s, 0, jump_ratio, s);
  const Eigen::Vector3f* left = ContinuousNeighbour(cloud, u, v, -s, 0, jump_ratio, s);
  const Eigen::Vector3f* down = ContinuousNeighbour(cloud, u, v, 0, s, jump_ratio, s);
  const Eigen::Vector3f* up = ContinuousNeighbour(cloud, u, v, 0, -s, jump_ratio, s);
  if ((right == nullptr && left == nullptr) || (down == nullptr && up == nullptr)) return nan3;
  // Central differences where both sides exist, one-sided at borders and depth edges.
  const Eigen::Vector3f dx = (right ? *right : p) - (left ? *left : p);
  const Eigen::Vector3f dy = (down ? *down : p) - (up ? *up : p);
  Eigen::Vector3f n = dx.cross(dy);
  const float norm = n.norm();
  if (!(norm > 0.f)) return nan3;
  n /= norm;
  return n.dot(p) > 0.f ? Eigen::Vector3f(-n) : n;
}

}  // namespace

std::vector<Eigen::Vector3f> ComputeNormals(const OrganizedCloud& cloud_C, int step_px,
                                            float jump_ratio) {
  std::vector<Eigen::Vector3f> normals(
      cloud_C.size(), Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  for (int v = 0; v < cloud_C.height; ++v) {
    for (int u = 0; u < cloud_C.width; ++u) {
      const int i = v * cloud_C.width + u;
      if (cloud_C.IsValid(i)) normals[i] = PixelNormal(cloud_C, u, v, step_px, jump_ratio);
    }
  }
  return normals;
}

// Supporting planes (table, floor, walls) in the spirit of Pham et al. 2016 (paper Sec. III-B):
// sequential RANSAC where one pixel and its normal form a hypothesis, refined by PCA; a plane is
// kept only when its metric area is large, so box faces stay ordinary surfaces.

namespace {

constexpr int kSampleStridePx = 6;
// Hypotheses are scored on at most this many samples (the refit and labelling use all).
constexpr size_t kMaxScoredSamples = 1500;
constexpr float kPi = 3.14159265358979f;

struct Plane {
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  float offset = 0.f;  // n . p + offset = 0
};

struct InlierTest {
  float distance_m;
  float cos_angle;
  bool operator()(const Plane& plane, const Eigen::Vector3f& p, const Eigen::Vector3f& n) const {
    // Kinect depth noise grows with depth squared; keep a floor for close range.
    const float tolerance = distance_m * std::max(1.f, p.z() * p.z());
    return std::abs(plane.normal.dot(p) + plane.offset) <= tolerance &&
           plane.normal.dot(n) >= cos_angle;
  }
};

Plane FitPlane(const OrganizedCloud& cloud, const std::vector<int>& indices) {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (int i : indices) mean += cloud.points_C[i];
  mean /= static_cast<float>(indices.size());
  Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
  for (int i : indices) {
    const Eigen::Vector3f d = cloud.points_C[i] - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(cov);
  Plane plane;
  plane.normal = solver.eigenvectors().col(0);
  if (plane.normal.dot(mean) > 0.f) plane.normal = -plane.normal;
  plane.offset = -plane.normal.dot(mean);
  return plane;
}

// Best point+normal hypothesis over the remaining samples, refined on its inliers.
bool FindPlane(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
               const std::vector<int>& samples, const InlierTest& inlier, int iterations,
               std::mt19937* rng, Plane* plane) {
  std::uniform_int_distribution<size_t> pick(0, samples.size() - 1);
  size_t best_count = 0;
  const size_t stride = std::max<size_t>(1, samples.size() / kMaxScoredSamples);
  for (int it = 0; it < iterations; ++it) {
    const int seed = samples[pick(*rng)];
    Plane candidate{normals[seed], -normals[seed].dot(cloud.points_C[seed])};
    size_t count = 0;
    for (size_t k = 0; k < samples.size(); k += stride) {
      const int i = samples[k];
      count += inlier(candidate, cloud.points_C[i], normals[i]) ? 1 : 0;
    }
    if (count > best_count) {
      best_count = count;
      *plane = candidate;
    }
  }
  if (best_count < 3) return false;  // too few to refit
  std::vector<int> inliers;
  for (int i : samples) {
    if (inlier(*plane, cloud.points_C[i], normals[i])) inliers.push_back(i);
  }
  *plane = FitPlane(cloud, inliers);
  return true;
}

// Labels every free inlier pixel with `id` when the plane's metric area is large enough.
bool AssignPlane(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
                 const Plane& plane, const InlierTest& inlier, float focal_px, float min_area_m2,
                 int id, std::vector<std::int8_t>* plane_of_pixel) {
  std::vector<int> members;
  float area_m2 = 0.f;
  for (size_t i = 0; i < cloud.size(); ++i) {
    if ((*plane_of_pixel)[i] >= 0 || !cloud.IsValid(static_cast<int>(i))) continue;
    const Eigen::Vector3f& p = cloud.points_C[i];
    if (!normals[i].allFinite() || !inlier(plane, p, normals[i])) continue;
    members.push_back(static_cast<int>(i));
    area_m2 += PixelAreaM2(p, plane.normal, focal_px);
  }
  if (area_m2 < min_area_m2) return false;
  for (int i : members) (*plane_of_pixel)[i] = static_cast<std::int8_t>(id);
  return true;
}

}  // namespace

int DetectSupportingPlanes(const OrganizedCloud& cloud_C,
                           const std::vector<Eigen::Vector3f>& normals,
                           const SegmenterConfig& config, float focal_px,
                           std::vector<std::int8_t>* plane_of_pixel) {
  plane_of_pixel->assign(cloud_C.size(), -1);
  std::vector<int> samples;
  for (int v = kSampleStridePx / 2; v < cloud_C.height; v += kSampleStridePx) {
    for (int u = kSampleStridePx / 2; u < cloud_C.width; u += kSampleStridePx) {
      const int i = v * cloud_C.width + u;
      if (cloud_C.IsValid(i) && normals[i].allFinite()) samples.push_back(i);
    }
  }
  const InlierTest inlier{config.plane_distance_m,
                          std::cos(config.plane_normal_angle_deg * kPi / 180.f)};

  std::mt19937 rng(12345);  // fixed seed: the same cloud always gives the same planes
  int found = 0;
  while (found < config.max_planes && samples.size() >= 16) {
    Plane plane;
    if (!FindPlane(cloud_C, normals, samples, inlier, config.plane_iterations, &rng, &plane)) break;
    if (!AssignPlane(cloud_C, normals, plane, inlier, focal_px, config.min_plane_area_m2, found,
                     plane_of_pixel)) {
      break;  // hypotheses are tried largest first, so smaller ones would fail too
    }
    std::vector<int> rest;
    for (int i : samples) {
      if ((*plane_of_pixel)[i] < 0) rest.push_back(i);
    }
    samples.swap(rest);
    ++found;
  }
  return found;
}

// Supervoxels on the image grid and their adjacency graph (paper Sec. III-B). Cells of
// cell_px x cell_px pixels are split into depth-continuous groups of one plane id, so a
// supervoxel never straddles a depth edge or a plane boundary.

namespace {

struct CellRange {
  int u0, v0, u1, v1;  // half-open pixel range of one cell
};

// Flood fill from `seed` inside the cell; returns the pixel indices of the new supervoxel.
void FillSupervoxel(const OrganizedCloud& cloud, const std::vector<std::int8_t>& plane_of_pixel,
                    const CellRange& cell, float jump_ratio, int seed, int id,
                    std::vector<int>* supervoxel_of_pixel, std::vector<int>* members) {
  members->clear();
  members->push_back(seed);
  (*supervoxel_of_pixel)[seed] = id;
  const int w = cloud.width;
  for (size_t head = 0; head < members->size(); ++head) {
    const int i = (*members)[head];
    const int u = i % w;
    const int v = i / w;
    const int nu[4] = {u + 1, u - 1, u, u};
    const int nv[4] = {v, v, v + 1, v - 1};
    for (int k = 0; k < 4; ++k) {
      if (nu[k] < cell.u0 || nu[k] >= cell.u1 || nv[k] < cell.v0 || nv[k] >= cell.v1) continue;
      const int j = nv[k] * w + nu[k];
      if ((*supervoxel_of_pixel)[j] >= 0 || !cloud.IsValid(j)) continue;
      if (plane_of_pixel[j] != plane_of_pixel[i]) continue;
      if (!DepthContinuous(cloud.points_C[i].z(), cloud.points_C[j].z(), jump_ratio, 1)) continue;
      (*supervoxel_of_pixel)[j] = id;
      members->push_back(j);
    }
  }
}

Supervoxel Summarize(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
                     const std::vector<std::int8_t>& plane_of_pixel,
                     const std::vector<int>& members, float focal_px) {
  Supervoxel sv;
  sv.pixels = static_cast<int>(members.size());
  sv.plane = plane_of_pixel[members.front()];
  Eigen::Vector3f normal_sum = Eigen::Vector3f::Zero();
  for (int i : members) {
    sv.centroid += cloud.points_C[i];
    if (normals[i].allFinite()) normal_sum += normals[i];
  }
  sv.centroid /= static_cast<float>(members.size());
  const float norm = normal_sum.norm();
  sv.has_normal = norm > 0.f;
  if (sv.has_normal) sv.normal = normal_sum / norm;
  const Eigen::Vector3f facing = sv.has_normal ? sv.normal : Eigen::Vector3f(-sv.centroid);
  sv.area_m2 =
      static_cast<float>(sv.pixels) * PixelAreaM2(sv.centroid, facing.normalized(), focal_px);
  return sv;
}

}  // namespace

void BuildSupervoxels(const OrganizedCloud& cloud_C, const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<std::int8_t>& plane_of_pixel, const SegmenterConfig& config,
                      float focal_px, std::vector<int>* supervoxel_of_pixel,
                      std::vector<Supervoxel>* supervoxels) {
  supervoxel_of_pixel->assign(cloud_C.size(), -1);
  supervoxels->clear();
  std::vector<int> members;
  const int c = config.cell_px;
  for (int v0 = 0; v0 < cloud_C.height; v0 += c) {
    for (int u0 = 0; u0 < cloud_C.width; u0 += c) {
      const CellRange cell{u0, v0, std::min(u0 + c, cloud_C.width),
                           std::min(v0 + c, cloud_C.height)};
      for (int v = cell.v0; v < cell.v1; ++v) {
        for (int u = cell.u0; u < cell.u1; ++u) {
          const int i = v * cloud_C.width + u;
          if ((*supervoxel_of_pixel)[i] >= 0 || !cloud_C.IsValid(i)) continue;
          FillSupervoxel(cloud_C, plane_of_pixel, cell, config.depth_jump_ratio, i,
                         static_cast<int>(supervoxels->size()), supervoxel_of_pixel, &members);
          supervoxels->push_back(Summarize(cloud_C, normals, plane_of_pixel, members, focal_px));
        }
      }
    }
  }
}

std::vector<GraphEdge> BuildAdjacencyGraph(const OrganizedCloud& cloud_C,
                                           const std::vector<int>& supervoxel_of_pixel,
                                           const std::vector<Supervoxel>& supervoxels,
                                           const SegmenterConfig& config) {
  std::vector<std::uint64_t> keys;
  const int w = cloud_C.width;
  auto consider = [&](int i, int j) {
    const int a = supervoxel_of_pixel[i];
    const int b = supervoxel_of_pixel[j];
    if (a < 0 || b < 0 || a == b) return;
    // Pixels across a depth edge are not neighbours: objects apart in depth never merge.
    if (!DepthContinuous(cloud_C.points_C[i].z(), cloud_C.points_C[j].z(), config.depth_jump_ratio,
                         1)) {
      return;
    }
    const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
                              static_cast<std::uint32_t>(std::max(a, b));
    if (keys.empty() || keys.back() != key) keys.push_back(key);
  };
  for (int v = 0; v < cloud_C.height; ++v) {
    for (int u = 0; u < w; ++u) {
      const int i = v * w + u;
      if (u + 1 < w) consider(i, i + 1);
      if (v + 1 < cloud_C.height) consider(i, i + w);
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<GraphEdge> edges;
  edges.reserve(keys.size());
  for (std::uint64_t key : keys) {
    GraphEdge e;
    e.a = static_cast<int>(key >> 32);
    e.b = static_cast<int>(key & 0xffffffffu);
    e.weight = EdgeWeight(supervoxels[e.a], supervoxels[e.b], config.convex_tolerance);
    edges.push_back(e);
  }
  return edges;
}

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
  bool changed = false;
  for (size_t s = 0; s < svs.size(); ++s) {
    if (svs[s].plane < 0) continue;
    if (area_m2[patches.Find(static_cast<int>(s))] < config.min_plane_patch_area_m2) {
      svs[s].plane = -1;
      changed = true;
    }
  }
  if (!changed) return;
  for (seg::GraphEdge& e : *edges) {
    e.weight = seg::EdgeWeight(svs[e.a], svs[e.b], config.convex_tolerance);
  }
}

// Kruskal over edges sorted by weight: merge when the edge is no heavier than both segments'
// Int(C) + k / |C| (Felzenszwalb & Huttenlocher 2004), then absorb segments under the size floor.
void CutGraph(std::vector<seg::GraphEdge>* edges, const SegmenterConfig& config,
              Components* components) {
  std::stable_sort(
      edges->begin(), edges->end(),
      [](const seg::GraphEdge& x, const seg::GraphEdge& y) { return x.weight < y.weight; });
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
    all_pixels[id] += supervoxels[s].pixels;
    if (supervoxels[s].plane >= 0) plane_pixels[id] += supervoxels[s].pixels;
  }
  for (size_t i = 0; i < cloud.size(); ++i) {
    const int s = supervoxel_of_pixel[i];
    if (s >= 0) result.labels[i] = segment_of_root[components->Find(s)];
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

SegmentationResult Segment(const OrganizedCloud& cloud_C, const SegmenterConfig& config) {
  const size_t n = static_cast<size_t>(std::max(0, cloud_C.width)) * std::max(0, cloud_C.height);
  if (n == 0 || cloud_C.points_C.size() != n) {
    SegmentationResult empty;
    empty.labels.assign(cloud_C.points_C.size(), -1);
    return empty;
  }
  if (!config.IsValid(nullptr)) return SingleSegment(cloud_C);
  const std::vector<Eigen::Vector3f> normals =
      reference::ComputeNormals(cloud_C, config.normal_step_px, config.depth_jump_ratio);
  const float focal_px = seg::EstimateFocalPx(cloud_C, kFallbackFocalPx);
  std::vector<std::int8_t> plane_of_pixel;
  reference::DetectSupportingPlanes(cloud_C, normals, config, focal_px, &plane_of_pixel);
  std::vector<int> supervoxel_of_pixel;
  std::vector<seg::Supervoxel> supervoxels;
  reference::BuildSupervoxels(cloud_C, normals, plane_of_pixel, config, focal_px,
                              &supervoxel_of_pixel, &supervoxels);
  std::vector<seg::GraphEdge> edges =
      reference::BuildAdjacencyGraph(cloud_C, supervoxel_of_pixel, supervoxels, config);
  DropSmallPlanePatches(config, &supervoxels, &edges);
  Components components(supervoxels);
  CutGraph(&edges, config, &components);
  return Relabel(cloud_C, supervoxel_of_pixel, supervoxels, &components);
}

}  // namespace objmap::reference
