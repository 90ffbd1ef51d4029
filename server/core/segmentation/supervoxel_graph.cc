// Supervoxels on the image grid and their adjacency graph (paper Sec. III-B). Cells of
// cell_px x cell_px pixels are split into depth-continuous groups of one plane id, so a
// supervoxel never straddles a depth edge or a plane boundary.
#include <algorithm>
#include <cstdint>

#include "segmentation/segmentation_internal.h"

namespace objmap::seg {
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

float EdgeWeight(const Supervoxel& s_i, const Supervoxel& s_j, float convex_tolerance) {
  if (s_i.plane >= 0 && s_i.plane == s_j.plane) return 0.f;
  if (s_i.plane >= 0 || s_j.plane >= 0) return 1.f;
  if (!s_i.has_normal || !s_j.has_normal) return 1.f;
  const float dissimilarity = 1.f - std::clamp(s_i.normal.dot(s_j.normal), -1.f, 1.f);
  // LCCP (Stein et al. 2014) with normals facing the camera, i.e. outwards on visible surfaces:
  // on a convex surface c = R n locally, so (c_i - c_j).(n_i - n_j) > 0.
  const Eigen::Vector3f between = s_i.centroid - s_j.centroid;
  const bool convex = between.dot(s_i.normal - s_j.normal) > -convex_tolerance * between.norm();
  return convex ? dissimilarity * dissimilarity : dissimilarity;
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

}  // namespace objmap::seg
