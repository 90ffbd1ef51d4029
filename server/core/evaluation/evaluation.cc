#include "evaluation/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <unordered_map>

#include "evaluation/voxel_set.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

struct Box {
  Eigen::Vector3d min, max;
  [[nodiscard]] double Volume() const { return (max - min).cwiseMax(0.0).prod(); }
};

// Axis-aligned box around a real object's oriented box.
Box WorldBox(const GroundTruthObject& object) {
  const Eigen::Vector3d half_extent = object.T_W_B.linear().cwiseAbs() * (0.5 * object.size_m);
  return {object.T_W_B.translation() - half_extent, object.T_W_B.translation() + half_extent};
}

double IntersectionVolume(const Box& a, const Box& b) {
  return (a.max.cwiseMin(b.max) - a.min.cwiseMax(b.min)).cwiseMax(0.0).prod();
}

double Iou(const Box& a, const Box& b) {
  const double intersection = IntersectionVolume(a, b);
  const double united = a.Volume() + b.Volume() - intersection;
  return united > 0.0 ? intersection / united : 0.0;
}

// True when `p_B` (in the real object's box frame) lies in its box grown by `margin_m`.
bool InsideGrownBox(const Eigen::Vector3d& p_B, const GroundTruthObject& real, double margin_m) {
  const Eigen::Vector3d half = 0.5 * real.size_m + Eigen::Vector3d::Constant(margin_m);
  return (p_B.cwiseAbs().array() <= half.array()).all();
}

// The mapped object can stand for the real one (classes aside).
bool CanStandFor(const MappedObject& mapped, const GroundTruthObject& real,
                 const EvaluationConfig& config) {
  if (InsideGrownBox(real.T_W_B.inverse() * mapped.centroid_W, real, config.centroid_margin_m)) {
    return true;
  }
  return Iou({mapped.min_W, mapped.max_W}, WorldBox(real)) >= config.min_box_iou;
}

// How many real objects of the mapped object's class it lies substantially on (see
// EvaluationConfig::merge_point_share). A model point counts for a real object only when it lies
// in that object's grown box and in no other's of the class: boxes of mugs side by side overlap,
// and a model of one mug must not count for its neighbour through the shared part.
int CoveredObjects(const MappedObject& mapped, const std::vector<GroundTruthObject>& real,
                   const EvaluationConfig& config) {
  std::vector<std::size_t> same_class;
  for (std::size_t r = 0; r < real.size(); ++r) {
    if (real[r].class_id == mapped.class_id) same_class.push_back(r);
  }
  int covered = 0;
  if (mapped.model_W.empty()) {
    for (std::size_t r : same_class) {
      const Box real_box = WorldBox(real[r]);
      if (real_box.Volume() > 0.0 && IntersectionVolume({mapped.min_W, mapped.max_W}, real_box) >=
                                         config.merge_box_share * real_box.Volume()) {
        ++covered;
      }
    }
    return covered;
  }
  std::vector<Eigen::Isometry3d> T_B_W;
  for (std::size_t r : same_class) T_B_W.push_back(real[r].T_W_B.inverse());
  std::vector<std::size_t> exclusive(same_class.size(), 0);
  for (const Eigen::Vector3f& p : mapped.model_W) {
    int inside = 0;
    std::size_t last = 0;
    for (std::size_t k = 0; k < same_class.size(); ++k) {
      if (InsideGrownBox(T_B_W[k] * p.cast<double>(), real[same_class[k]],
                         config.merge_box_margin_m)) {
        ++inside, last = k;
      }
    }
    if (inside == 1) ++exclusive[last];
  }
  for (std::size_t count : exclusive) {
    if (static_cast<double>(count) >=
        config.merge_point_share * static_cast<double>(mapped.model_W.size())) {
      ++covered;
    }
  }
  return covered;
}

// Nearest-neighbour distances through a hash grid of cell `cell_m` over `targets`.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3f>& targets, double cell_m) : cell_m_(cell_m) {
    for (const Eigen::Vector3f& p : targets) cells_[PackVoxel(Cell(p))].push_back(p);
  }
  // Distance to the nearest target, capped at `cap_m` (searched within the cells that reach it).
  [[nodiscard]] double Distance(const Eigen::Vector3f& p, double cap_m) const {
    const Eigen::Vector3i centre = Cell(p);
    const int reach = static_cast<int>(std::ceil(cap_m / cell_m_));
    double best2 = cap_m * cap_m;
    for (int dx = -reach; dx <= reach; ++dx) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dz = -reach; dz <= reach; ++dz) {
          auto it = cells_.find(PackVoxel(centre + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const Eigen::Vector3f& q : it->second) {
            best2 = std::min(best2, static_cast<double>((p - q).squaredNorm()));
          }
        }
      }
    }
    return std::sqrt(best2);
  }

 private:
  [[nodiscard]] Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
    return VoxelOf(p.cast<double>(), cell_m_);
  }
  double cell_m_;
  std::unordered_map<std::int64_t, std::vector<Eigen::Vector3f>> cells_;
};

// Closest point to `p` on triangle (a, b, c): the region of the triangle's Voronoi diagram that
// holds p decides between a corner, an edge and the face.
Eigen::Vector3f ClosestOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                  const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.f && d2 <= 0.f) return a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.f && d1 >= 0.f && d3 <= 0.f) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.f && d2 >= 0.f && d6 <= 0.f) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.f && (d4 - d3) >= 0.f && (d5 - d6) >= 0.f) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const float denominator = va + vb + vc;
  if (!(std::abs(denominator) > 0.f)) return a;  // degenerate triangle
  return a + ab * (vb / denominator) + ac * (vc / denominator);
}

// Exact distances to a triangle mesh through a hash grid: each triangle is listed in the cells
// its bounding box overlaps; a query searches rings of cells outwards and stops once the ring
// cannot hold anything nearer than the best found.
class TriangleGrid {
 public:
  TriangleGrid(const std::vector<Eigen::Vector3f>& vertices,
               const std::vector<Eigen::Vector3i>& triangles, double cell_m)
      : vertices_(vertices), triangles_(triangles), cell_m_(cell_m) {
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Eigen::Vector3i& tri = triangles[t];
      const Eigen::Vector3f lo =
          vertices[tri[0]].cwiseMin(vertices[tri[1]]).cwiseMin(vertices[tri[2]]);
      const Eigen::Vector3f hi =
          vertices[tri[0]].cwiseMax(vertices[tri[1]]).cwiseMax(vertices[tri[2]]);
      const Eigen::Vector3i a = Cell(lo), b = Cell(hi);
      for (int x = a.x(); x <= b.x(); ++x) {
        for (int y = a.y(); y <= b.y(); ++y) {
          for (int z = a.z(); z <= b.z(); ++z) {
            cells_[PackVoxel({x, y, z})].push_back(static_cast<int>(t));
          }
        }
      }
    }
  }

  // Distance to the nearest triangle, capped at `cap_m`.
  [[nodiscard]] double Distance(const Eigen::Vector3f& p, double cap_m) const {
    const Eigen::Vector3i centre = Cell(p);
    const int reach = static_cast<int>(std::ceil(cap_m / cell_m_));
    double best2 = cap_m * cap_m;
    for (int ring = 0; ring <= reach; ++ring) {
      // Everything in this ring or beyond lies at least (ring - 1) cells away.
      const double ring_min = std::max(0, ring - 1) * cell_m_;
      if (ring_min * ring_min >= best2) break;
      for (int dx = -ring; dx <= ring; ++dx) {
        for (int dy = -ring; dy <= ring; ++dy) {
          for (int dz = -ring; dz <= ring; ++dz) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
            auto it = cells_.find(PackVoxel(centre + Eigen::Vector3i(dx, dy, dz)));
            if (it == cells_.end()) continue;
            for (int t : it->second) {
              const Eigen::Vector3i& tri = triangles_[t];
              const Eigen::Vector3f q =
                  ClosestOnTriangle(p, vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]]);
              best2 = std::min(best2, static_cast<double>((p - q).squaredNorm()));
            }
          }
        }
      }
    }
    return std::sqrt(best2);
  }

 private:
  [[nodiscard]] Eigen::Vector3i Cell(const Eigen::Vector3f& p) const {
    return VoxelOf(p.cast<double>(), cell_m_);
  }
  const std::vector<Eigen::Vector3f>& vertices_;
  const std::vector<Eigen::Vector3i>& triangles_;
  double cell_m_;
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
};

// Mean capped distance from every point of `from` to the mesh; negative when either is empty.
double MeanDistanceToMesh(const std::vector<Eigen::Vector3f>& from, const GroundTruthObject& real,
                          double cap_m) {
  if (from.empty() || real.mesh_triangles.empty()) return -1.0;
  const TriangleGrid grid(real.mesh_vertices_W, real.mesh_triangles, 0.02);
  double sum = 0.0;
  for (const Eigen::Vector3f& p : from) sum += grid.Distance(p, cap_m);
  return sum / static_cast<double>(from.size());
}

// Mean capped distance from every point of `from` to `to`; negative when either is empty.
double MeanDistance(const std::vector<Eigen::Vector3f>& from,
                    const std::vector<Eigen::Vector3f>& to, double cap_m) {
  if (from.empty() || to.empty()) return -1.0;
  const PointGrid grid(to, std::max(0.01, cap_m / 4.0));
  double sum = 0.0;
  for (const Eigen::Vector3f& p : from) sum += grid.Distance(p, cap_m);
  return sum / static_cast<double>(from.size());
}

}  // namespace

bool EvaluationConfig::IsValid(std::string* why) const {
  if (!(centroid_margin_m >= 0.0) || !(min_box_iou > 0.0 && min_box_iou <= 1.0) ||
      !(merge_box_share > 0.0 && merge_box_share <= 1.0) ||
      !(merge_point_share > 0.0 && merge_point_share <= 1.0) || !(merge_box_margin_m >= 0.0) ||
      !(max_model_distance_m > 0.0) || min_visible_frames < 0) {
    *why =
        "EvaluationConfig: centroid_margin_m >= 0, min_box_iou, merge_box_share and "
        "merge_point_share in (0, 1], merge_box_margin_m >= 0, "
        "max_model_distance_m > 0 and min_visible_frames >= 0 are required";
    return false;
  }
  return true;
}

double ClassCounts::Precision() const {
  const int claims = true_positives + false_positives + duplicates;
  return claims == 0 ? 1.0 : static_cast<double>(true_positives) / claims;
}

double ClassCounts::Recall() const {
  return real == 0 ? 1.0 : static_cast<double>(true_positives) / real;
}

void ClassCounts::Add(const ClassCounts& other) {
  real += other.real;
  mapped += other.mapped;
  true_positives += other.true_positives;
  false_positives += other.false_positives;
  misses += other.misses;
  duplicates += other.duplicates;
  merges += other.merges;
  wrong_labels += other.wrong_labels;
  unseen += other.unseen;
}

ObjectEvaluation EvaluateObjects(const std::vector<GroundTruthObject>& ground_truth,
                                 const std::vector<MappedObject>& mapped,
                                 const EvaluationConfig& config) {
  ObjectEvaluation result;
  std::vector<GroundTruthObject> real;
  for (const GroundTruthObject& object : ground_truth) {
    if (object.visible_frames >= 0 && object.visible_frames < config.min_visible_frames) {
      ++result.per_class[object.class_id].unseen;
    } else {
      real.push_back(object);
    }
  }
  for (const GroundTruthObject& object : real) ++result.per_class[object.class_id].real;
  // Each mapped object stands for the nearest real object of its class it can stand for.
  std::map<std::size_t, std::vector<std::size_t>> standing_for;  // real index -> mapped indices
  std::vector<std::size_t> unknown;
  for (std::size_t m = 0; m < mapped.size(); ++m) {
    if (mapped[m].class_id == kUnknownClassId) {
      unknown.push_back(m);
      continue;
    }
    ClassCounts& counts = result.per_class[mapped[m].class_id];
    ++counts.mapped;
    std::size_t best = real.size();
    double best_distance = std::numeric_limits<double>::infinity();
    bool on_other_class = false;
    for (std::size_t r = 0; r < real.size(); ++r) {
      const bool same_class = real[r].class_id == mapped[m].class_id;
      if (!CanStandFor(mapped[m], real[r], config)) continue;
      if (!same_class) {
        on_other_class = true;
        continue;
      }
      const double distance = (mapped[m].centroid_W - real[r].T_W_B.translation()).norm();
      if (distance < best_distance) {
        best_distance = distance;
        best = r;
      }
    }
    if (CoveredObjects(mapped[m], real, config) >= 2) ++counts.merges;
    if (best < real.size()) {
      standing_for[best].push_back(m);
    } else {
      ++counts.false_positives;
      if (on_other_class) ++counts.wrong_labels;
    }
  }
  std::vector<double> accuracies;
  for (std::size_t r = 0; r < real.size(); ++r) {
    ClassCounts& counts = result.per_class[real[r].class_id];
    auto it = standing_for.find(r);
    if (it == standing_for.end()) {
      ++counts.misses;
      continue;
    }
    ++counts.true_positives;
    counts.duplicates += static_cast<int>(it->second.size()) - 1;
    // The match is the fullest model; the others are the duplicates.
    const std::size_t m =
        *std::max_element(it->second.begin(), it->second.end(), [&](std::size_t a, std::size_t b) {
          return mapped[a].model_W.size() < mapped[b].model_W.size();
        });
    ObjectMatch match;
    match.real_id = real[r].id;
    match.mapped_id = mapped[m].id;
    match.model_to_surface_m =
        real[r].mesh_triangles.empty()
            ? MeanDistance(mapped[m].model_W, real[r].surface_W, config.max_model_distance_m)
            : MeanDistanceToMesh(mapped[m].model_W, real[r], config.max_model_distance_m);
    match.surface_to_model_m =
        MeanDistance(real[r].surface_W, mapped[m].model_W, config.max_model_distance_m);
    if (match.model_to_surface_m >= 0.0) accuracies.push_back(match.model_to_surface_m);
    result.matches.push_back(match);
  }
  std::set<std::size_t> missed_marked;
  for (std::size_t m : unknown) {
    ++result.unknown.mapped;
    bool on_real = false, on_missed = false;
    for (std::size_t r = 0; r < real.size(); ++r) {
      if (!CanStandFor(mapped[m], real[r], config)) continue;
      on_real = true;
      if (standing_for.count(r) == 0) {
        on_missed = true;
        missed_marked.insert(r);
      }
    }
    result.unknown.on_real += on_real ? 1 : 0;
    result.unknown.on_missed += on_missed ? 1 : 0;
  }
  result.unknown.missed_marked = static_cast<int>(missed_marked.size());
  for (const auto& [class_id, counts] : result.per_class) result.totals.Add(counts);
  if (!accuracies.empty()) {
    double sum = 0.0;
    for (double a : accuracies) sum += a;
    result.mean_model_to_surface_m = sum / static_cast<double>(accuracies.size());
  }
  return result;
}

std::map<int, ClassCounts> ScoreCounts(const std::map<int, CountRange>& expected,
                                       const std::map<int, int>& found) {
  std::map<int, ClassCounts> scores;
  for (const auto& [class_id, range] : expected) {
    ClassCounts& counts = scores[class_id];
    const auto it = found.find(class_id);
    const int count = it == found.end() ? 0 : it->second;
    counts.real = std::clamp(count, range.min, range.max);
    counts.mapped = count;
    counts.false_positives = std::max(0, count - range.max);
    counts.misses = std::max(0, range.min - count);
    counts.true_positives = count - counts.false_positives;
  }
  for (const auto& [class_id, count] : found) {
    if (expected.count(class_id) > 0) continue;
    ClassCounts& counts = scores[class_id];
    counts.mapped = count;
    counts.false_positives = count;
  }
  return scores;
}

}  // namespace objmap
