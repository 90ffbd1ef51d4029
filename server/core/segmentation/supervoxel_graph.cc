// Supervoxels on the image grid and their adjacency graph (paper Sec. III-B). Cells of
// cell_px x cell_px pixels are split into depth-continuous groups of one plane id, so a
// supervoxel never straddles a depth edge or a plane boundary.
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cstdint>
#include <utility>

#include "segmentation/segmentation_internal.h"

namespace objmap::seg {
namespace {

struct CellRange {
  int u0, v0, u1, v1;  // half-open pixel range of one cell
};

// Flood fill from the seed pixel inside the cell, summing points and normals in breadth-first
// order as the pixels leave the queue. Pixel coordinates travel with the queue, so no pixel index
// is divided back into (u, v).
class SupervoxelGrower {
 public:
  SupervoxelGrower(const OrganizedCloud& cloud, const std::vector<Eigen::Vector3f>& normals,
                   const std::vector<std::int8_t>& plane_of_pixel, float jump_ratio, float focal_px,
                   int cell_px, std::vector<int>* supervoxel_of_pixel)
      : cloud_(cloud),
        normals_(normals),
        plane_of_pixel_(plane_of_pixel),
        jump_ratio_(jump_ratio),
        focal_px_(focal_px),
        owner_(*supervoxel_of_pixel),
        queue_(static_cast<size_t>(cell_px) * cell_px),
        cell_px_(cell_px),
        whole_cell_order_(WholeCellOrder(cell_px, cloud.width)) {}

  // A full cell whose pixels are all valid, on one plane id and depth-continuous with their
  // neighbours inside the cell is one supervoxel, and the fill from its corner visits it in the
  // same order every time: that order is computed once and replayed. Most cells of a frame are
  // such cells. False (nothing changed) for any other cell.
  bool GrowWholeCell(const CellRange& cell, int id, Supervoxel* sv) {
    const int w = cloud_.width;
    const int c = cell_px_;
    if (cell.u1 - cell.u0 != c || cell.v1 - cell.v0 != c) return false;
    const int corner = cell.v0 * w + cell.u0;
    const std::int8_t plane = plane_of_pixel_[corner];
    for (int dv = 0; dv < c; ++dv) {
      for (int du = 0, i = corner + dv * w; du < c; ++du, ++i) {
        const float z = cloud_.points_C[i].z();
        if (!std::isfinite(z) || plane_of_pixel_[i] != plane) return false;
        if (du + 1 < c && !DepthContinuous(z, cloud_.points_C[i + 1].z(), jump_ratio_, 1)) {
          return false;
        }
        if (dv + 1 < c && !DepthContinuous(z, cloud_.points_C[i + w].z(), jump_ratio_, 1)) {
          return false;
        }
      }
    }
    *sv = Supervoxel();
    sv->plane = plane;
    Eigen::Vector3f normal_sum = Eigen::Vector3f::Zero();
    for (int offset : whole_cell_order_) {
      const int i = corner + offset;
      owner_[i] = id;
      sv->centroid += cloud_.points_C[i];
      if (normals_[i].allFinite()) normal_sum += normals_[i];
    }
    Finish(static_cast<int>(whole_cell_order_.size()), normal_sum, sv);
    return true;
  }

  Supervoxel Grow(const CellRange& cell, int seed_u, int seed_v, int id) {
    const int w = cloud_.width;
    queue_[0] = {seed_v * w + seed_u, seed_u, seed_v};
    tail_ = 1;
    owner_[queue_.front().i] = id;
    Supervoxel sv;
    sv.plane = plane_of_pixel_[queue_.front().i];
    Eigen::Vector3f normal_sum = Eigen::Vector3f::Zero();
    for (size_t head = 0; head < tail_; ++head) {
      const auto [i, u, v] = queue_[head];
      const Eigen::Vector3f& p = cloud_.points_C[i];
      sv.centroid += p;
      if (normals_[i].allFinite()) normal_sum += normals_[i];
      if (u + 1 < cell.u1) Visit(i + 1, u + 1, v, p.z(), sv.plane, id);
      if (u - 1 >= cell.u0) Visit(i - 1, u - 1, v, p.z(), sv.plane, id);
      if (v + 1 < cell.v1) Visit(i + w, u, v + 1, p.z(), sv.plane, id);
      if (v - 1 >= cell.v0) Visit(i - w, u, v - 1, p.z(), sv.plane, id);
    }
    Finish(static_cast<int>(tail_), normal_sum, &sv);
    return sv;
  }

 private:
  // Pixel offsets from a cell's corner in the order the fill visits a cell where every pixel
  // joins: breadth first from the corner, neighbours right, left, down, up.
  static std::vector<int> WholeCellOrder(int c, int width) {
    std::vector<std::pair<int, int>> queue = {{0, 0}};
    std::vector<bool> seen(static_cast<size_t>(c) * c, false);
    seen[0] = true;
    for (size_t head = 0; head < queue.size(); ++head) {
      const auto [u, v] = queue[head];
      const int next[4][2] = {{u + 1, v}, {u - 1, v}, {u, v + 1}, {u, v - 1}};
      for (const auto& [u2, v2] : next) {
        if (u2 < 0 || v2 < 0 || u2 >= c || v2 >= c || seen[v2 * c + u2]) continue;
        seen[v2 * c + u2] = true;
        queue.emplace_back(u2, v2);
      }
    }
    std::vector<int> offsets;
    for (const auto& [u, v] : queue) offsets.push_back(v * width + u);
    return offsets;
  }

  // Mean, normal and area from the sums of `pixels` pixels.
  void Finish(int pixels, const Eigen::Vector3f& normal_sum, Supervoxel* sv) const {
    sv->pixels = pixels;
    sv->centroid /= static_cast<float>(sv->pixels);
    const float norm = normal_sum.norm();
    sv->has_normal = norm > 0.f;
    if (sv->has_normal) sv->normal = normal_sum / norm;
    const Eigen::Vector3f facing = sv->has_normal ? sv->normal : Eigen::Vector3f(-sv->centroid);
    sv->area_m2 =
        static_cast<float>(sv->pixels) * PixelAreaM2(sv->centroid, facing.normalized(), focal_px_);
  }

  struct Entry {
    int i, u, v;
  };

  void Visit(int j, int u, int v, float z, std::int8_t plane, int id) {
    // DepthContinuous is false for an invalid (NaN) neighbour.
    if (owner_[j] >= 0 || plane_of_pixel_[j] != plane ||
        !DepthContinuous(z, cloud_.points_C[j].z(), jump_ratio_, 1)) {
      return;
    }
    owner_[j] = id;
    queue_[tail_++] = {j, u, v};
  }

  const OrganizedCloud& cloud_;
  const std::vector<Eigen::Vector3f>& normals_;
  const std::vector<std::int8_t>& plane_of_pixel_;
  const float jump_ratio_;
  const float focal_px_;
  std::vector<int>& owner_;
  std::vector<Entry> queue_;  // holds at most one cell
  size_t tail_ = 0;
  const int cell_px_;
  const std::vector<int> whole_cell_order_;
};

}  // namespace

void BuildSupervoxels(const OrganizedCloud& cloud_C, const std::vector<Eigen::Vector3f>& normals,
                      const std::vector<std::int8_t>& plane_of_pixel, const SegmenterConfig& config,
                      float focal_px, std::vector<int>* supervoxel_of_pixel,
                      std::vector<Supervoxel>* supervoxels) {
  supervoxel_of_pixel->assign(cloud_C.size(), -1);
  supervoxels->clear();
  SupervoxelGrower grower(cloud_C, normals, plane_of_pixel, config.depth_jump_ratio, focal_px,
                          config.cell_px, supervoxel_of_pixel);
  const int c = config.cell_px;
  for (int v0 = 0; v0 < cloud_C.height; v0 += c) {
    for (int u0 = 0; u0 < cloud_C.width; u0 += c) {
      const CellRange cell{u0, v0, std::min(u0 + c, cloud_C.width),
                           std::min(v0 + c, cloud_C.height)};
      Supervoxel whole;
      if (grower.GrowWholeCell(cell, static_cast<int>(supervoxels->size()), &whole)) {
        supervoxels->push_back(whole);
        continue;
      }
      for (int v = cell.v0; v < cell.v1; ++v) {
        for (int u = cell.u0; u < cell.u1; ++u) {
          const int i = v * cloud_C.width + u;
          if ((*supervoxel_of_pixel)[i] >= 0 || !cloud_C.IsValid(i)) continue;
          supervoxels->push_back(grower.Grow(cell, u, v, static_cast<int>(supervoxels->size())));
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
  // Neighbour pairs (low id, high id), repeats allowed; the same pair shows up on every row of a
  // cell border, so remembering the last partner of each supervoxel keeps most repeats out.
  std::vector<std::pair<int, int>> pairs;
  std::vector<int> last_partner(supervoxels.size(), -1);
  const int w = cloud_C.width;
  const std::vector<int>& owner = supervoxel_of_pixel;
  auto consider = [&](int i, int j) {
    const int a = owner[i];
    const int b = owner[j];
    if (a == b || a < 0 || b < 0) return;
    // Pixels across a depth edge are not neighbours: objects apart in depth never merge.
    if (!DepthContinuous(cloud_C.points_C[i].z(), cloud_C.points_C[j].z(), config.depth_jump_ratio,
                         1)) {
      return;
    }
    const int low = std::min(a, b);
    const int high = std::max(a, b);
    if (last_partner[low] == high) return;
    last_partner[low] = high;
    pairs.emplace_back(low, high);
  };
  // Most neighbour pairs lie inside one supervoxel; four pairs are compared at once and only
  // those with two owners go on.
  auto consider_pairs = [&](int first, int count, int offset) {
    int k = 0;
#if defined(__SSE2__)
    for (; k + 4 <= count; k += 4) {
      const int i = first + k;
      const __m128i here = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&owner[i]));
      const __m128i there = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&owner[i + offset]));
      const int same = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(here, there)));
      if (same == 0xf) continue;
      for (int lane = 0; lane < 4; ++lane) {
        if (!(same & (1 << lane))) consider(i + lane, i + lane + offset);
      }
    }
#endif
    for (; k < count; ++k) consider(first + k, first + k + offset);
  };
  for (int v = 0; v < cloud_C.height; ++v) {
    const int row = v * w;
    consider_pairs(row, w - 1, 1);
    if (v + 1 < cloud_C.height) consider_pairs(row, w, w);
  }
  // Edges in (a, b) order without repeats: bucket the pairs by their low id (counting sort), then
  // sort each supervoxel's handful of partners. The cut relies on this order for ties.
  std::vector<int> first(supervoxels.size() + 1, 0);
  for (const auto& pair : pairs) ++first[pair.first + 1];
  for (size_t s = 0; s < supervoxels.size(); ++s) first[s + 1] += first[s];
  std::vector<int> partners(pairs.size());
  std::vector<int> next(first.begin(), first.end() - 1);
  for (const auto& pair : pairs) partners[next[pair.first]++] = pair.second;
  std::vector<GraphEdge> edges;
  edges.reserve(pairs.size());
  for (size_t a = 0; a < supervoxels.size(); ++a) {
    const auto begin = partners.begin() + first[a];
    const auto end = partners.begin() + first[a + 1];
    std::sort(begin, end);
    for (auto b = begin; b != end; ++b) {
      if (b != begin && *b == *(b - 1)) continue;
      GraphEdge e;
      e.a = static_cast<int>(a);
      e.b = *b;
      e.weight = EdgeWeight(supervoxels[e.a], supervoxels[e.b], config.convex_tolerance);
      edges.push_back(e);
    }
  }
  return edges;
}

}  // namespace objmap::seg
