#include "posegraph/object_constraints.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>

#include "types/coco_classes.h"

namespace objmap {
namespace {

constexpr double kRadPerDeg = 0.017453292519943295;

// A balanced 3-d tree over a segment's points (a few thousand): nearest neighbour within a
// bound and all neighbours within a radius.
class PointTree {
 public:
  explicit PointTree(const std::vector<Eigen::Vector3f>& points)
      : points_(points), order_(points.size()), axis_(points.size(), 0) {
    std::iota(order_.begin(), order_.end(), 0);
    Build(0, static_cast<int>(order_.size()));
  }

  // Index of the nearest point within max_distance of q, or -1.
  int Nearest(const Eigen::Vector3f& q, float max_distance) const {
    int best = -1;
    float best_sq = max_distance * max_distance;
    NearestIn(0, static_cast<int>(order_.size()), q, &best, &best_sq);
    return best;
  }

  void Within(const Eigen::Vector3f& q, float radius, std::vector<int>* out) const {
    out->clear();
    WithinIn(0, static_cast<int>(order_.size()), q, radius, out);
  }

 private:
  void Build(int lo, int hi) {
    if (hi - lo <= 1) return;
    Eigen::Vector3f low = points_[static_cast<std::size_t>(order_[static_cast<std::size_t>(lo)])];
    Eigen::Vector3f high = low;
    for (int i = lo; i < hi; ++i) {
      const Eigen::Vector3f& p = points_[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])];
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
    int axis = 0;
    (high - low).maxCoeff(&axis);
    const int mid = (lo + hi) / 2;
    std::nth_element(order_.begin() + lo, order_.begin() + mid, order_.begin() + hi,
                     [&](int a, int b) {
                       return points_[static_cast<std::size_t>(a)][axis] <
                              points_[static_cast<std::size_t>(b)][axis];
                     });
    axis_[static_cast<std::size_t>(mid)] = static_cast<std::uint8_t>(axis);
    Build(lo, mid);
    Build(mid + 1, hi);
  }

  void NearestIn(int lo, int hi, const Eigen::Vector3f& q, int* best, float* best_sq) const {
    if (lo >= hi) return;
    const int mid = (lo + hi) / 2;
    const int index = order_[static_cast<std::size_t>(mid)];
    const Eigen::Vector3f& p = points_[static_cast<std::size_t>(index)];
    const float d_sq = (p - q).squaredNorm();
    if (d_sq <= *best_sq) {
      *best_sq = d_sq;
      *best = index;
    }
    if (hi - lo == 1) return;
    const int axis = axis_[static_cast<std::size_t>(mid)];
    const float diff = q[axis] - p[axis];
    if (diff < 0.f) {
      NearestIn(lo, mid, q, best, best_sq);
      if (diff * diff <= *best_sq) NearestIn(mid + 1, hi, q, best, best_sq);
    } else {
      NearestIn(mid + 1, hi, q, best, best_sq);
      if (diff * diff <= *best_sq) NearestIn(lo, mid, q, best, best_sq);
    }
  }

  void WithinIn(int lo, int hi, const Eigen::Vector3f& q, float radius,
                std::vector<int>* out) const {
    if (lo >= hi) return;
    const int mid = (lo + hi) / 2;
    const int index = order_[static_cast<std::size_t>(mid)];
    const Eigen::Vector3f& p = points_[static_cast<std::size_t>(index)];
    if ((p - q).squaredNorm() <= radius * radius) out->push_back(index);
    if (hi - lo == 1) return;
    const int axis = axis_[static_cast<std::size_t>(mid)];
    const float diff = q[axis] - p[axis];
    if (diff <= radius) WithinIn(lo, mid, q, radius, out);
    if (diff >= -radius) WithinIn(mid + 1, hi, q, radius, out);
  }

  const std::vector<Eigen::Vector3f>& points_;
  std::vector<int> order_;
  std::vector<std::uint8_t> axis_;  // split axis of the node whose median sits at this index
};

// Surface normals of a segment from the points within `radius` (PCA); zero where fewer than 5
// neighbours or no dominant plane.
std::vector<Eigen::Vector3f> SegmentNormals(const std::vector<Eigen::Vector3f>& points,
                                            const PointTree& tree, float radius) {
  std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f::Zero());
  std::vector<int> near;
  for (std::size_t i = 0; i < points.size(); ++i) {
    tree.Within(points[i], radius, &near);
    if (near.size() < 5) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int j : near) mean += points[static_cast<std::size_t>(j)].cast<double>();
    mean /= static_cast<double>(near.size());
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (int j : near) {
      const Eigen::Vector3d d = points[static_cast<std::size_t>(j)].cast<double>() - mean;
      scatter += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
    // A neighbourhood as thick as it is wide (a corner, noise) has no normal to trust.
    if (eigen.eigenvalues()(0) > 0.3 * eigen.eigenvalues()(1)) continue;
    normals[i] = eigen.eigenvectors().col(0).cast<float>();
  }
  return normals;
}

// Normal equations of the point-to-plane error at `pose`. Increments [dt; dtheta] move a point
// q to q + dt + dtheta x (q - centre): rotation about `centre`.
struct NormalEquations {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  int correspondences = 0;
};

NormalEquations Linearize(const std::vector<Eigen::Vector3f>& target,
                          const std::vector<Eigen::Vector3f>& normals, const PointTree& tree,
                          const std::vector<Eigen::Vector3f>& source,
                          const Eigen::Isometry3d& pose, const Eigen::Vector3d& centre,
                          double max_distance, double huber_m) {
  NormalEquations equations;
  for (const Eigen::Vector3f& p : source) {
    const Eigen::Vector3d q = pose * p.cast<double>();
    const int nearest = tree.Nearest(q.cast<float>(), static_cast<float>(max_distance));
    if (nearest < 0) continue;
    const Eigen::Vector3d n = normals[static_cast<std::size_t>(nearest)].cast<double>();
    if (n.isZero()) continue;
    const double r = n.dot(q - target[static_cast<std::size_t>(nearest)].cast<double>());
    Eigen::Matrix<double, 6, 1> J;
    J << n, (q - centre).cross(n);
    const double w = std::abs(r) <= huber_m ? 1.0 : huber_m / std::abs(r);
    equations.H.noalias() += w * J * J.transpose();
    equations.g.noalias() += w * r * J;
    ++equations.correspondences;
  }
  return equations;
}

double MedianDepth(const ColoredPoints& segment) {
  std::vector<float> depths;
  depths.reserve(segment.size());
  for (const Eigen::Vector3f& p : segment.points) depths.push_back(p.z());
  std::nth_element(depths.begin(), depths.begin() + static_cast<long>(depths.size() / 2),
                   depths.end());
  return depths[depths.size() / 2];
}

double AngleDeg(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle() / kRadPerDeg;
}

}  // namespace

bool ObjectConstraintConfig::IsValid(std::string* why) const {
  if (!(same_object_distance_m >= 0.0) || !(min_camera_separation_m >= 0.0) ||
      min_segment_points < 6 || max_pairs_per_object < 1 || icp_iterations < 1) {
    *why =
        "object constraints: distances >= 0, min_segment_points >= 6, max_pairs_per_object and "
        "icp_iterations >= 1";
    return false;
  }
  if (!(icp_first_max_distance_m >= icp_last_max_distance_m) || !(icp_last_max_distance_m > 0.0) ||
      !(min_overlap > 0.0 && min_overlap <= 1.0) ||
      !(information.min_eigenvalue_ratio > 0.0 && information.min_eigenvalue_ratio < 1.0) ||
      !(max_correction_m > 0.0) || !(max_correction_deg > 0.0) || !(point_sigma_m > 0.0) ||
      !(information.floor_sigma_m > 0.0) || !(information.floor_sigma_deg > 0.0)) {
    *why =
        "object constraints: icp distances positive and shrinking, min_overlap in (0, 1], "
        "min_eigenvalue_ratio in (0, 1), correction limits and sigmas positive";
    return false;
  }
  return true;
}

bool AlignSegments(const std::vector<Eigen::Vector3f>& target,
                   const std::vector<Eigen::Vector3f>& source, const ObjectConstraintConfig& config,
                   Eigen::Isometry3d* T_target_source, Eigen::Matrix<double, 6, 6>* information,
                   double* overlap) {
  if (overlap != nullptr) *overlap = 0.0;
  if (target.size() < 6 || source.size() < 6) return false;
  const PointTree tree(target);
  // Normals from a neighbourhood a few model voxels wide.
  const std::vector<Eigen::Vector3f> normals =
      SegmentNormals(target, tree, static_cast<float>(std::max(0.015, 3.0 * config.point_sigma_m)));
  // Rotations turn about the source segment's centre, and are scaled by its radius, so that the
  // subspace test compares like with like.
  Eigen::Vector3d centre_S = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3f& p : source) centre_S += p.cast<double>();
  centre_S /= static_cast<double>(source.size());
  double radius_sq = 0.0;
  for (const Eigen::Vector3f& p : source) radius_sq += (p.cast<double>() - centre_S).squaredNorm();
  const double radius_m = std::sqrt(radius_sq / static_cast<double>(source.size()));

  Eigen::Isometry3d pose = *T_target_source;
  for (int it = 0; it < config.icp_iterations; ++it) {
    const double fraction =
        config.icp_iterations > 1 ? static_cast<double>(it) / (config.icp_iterations - 1) : 1.0;
    const double max_distance =
        config.icp_first_max_distance_m +
        fraction * (config.icp_last_max_distance_m - config.icp_first_max_distance_m);
    const Eigen::Vector3d centre = pose * centre_S;
    const NormalEquations equations = Linearize(target, normals, tree, source, pose, centre,
                                                max_distance, config.point_sigma_m);
    if (equations.correspondences < 6) return false;
    // Steps only in the directions the surface fixes: the free ones stay where the pose-graph
    // estimate put them instead of following noise.
    const FixedDirections fixed =
        FixedDirectionsOf(equations.H, radius_m, config.information.min_eigenvalue_ratio);
    const Eigen::Matrix<double, 6, 1> g_scaled = fixed.scale * equations.g;
    Eigen::Matrix<double, 6, 1> step_scaled = Eigen::Matrix<double, 6, 1>::Zero();
    for (int i = 0; i < 6; ++i) {
      if (fixed.values(i) <= 0.0) continue;
      step_scaled -= fixed.vectors.col(i) * (fixed.vectors.col(i).dot(g_scaled) /
                                                fixed.values(i));
    }
    const Eigen::Matrix<double, 6, 1> step = fixed.scale * step_scaled;
    if (!step.allFinite()) return false;
    const Eigen::Vector3d rotation = step.tail<3>();
    Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
    if (rotation.norm() > 0.0) {
      turn = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).toRotationMatrix();
    }
    pose.linear() = turn * pose.linear();
    pose.translation() = turn * (pose.translation() - centre) + centre + step.head<3>();
  }
  int within = 0;
  for (const Eigen::Vector3f& p : source) {
    within += tree.Nearest((pose * p.cast<double>()).cast<float>(),
                           static_cast<float>(config.icp_last_max_distance_m)) >= 0;
  }
  const double fraction_within = static_cast<double>(within) / static_cast<double>(source.size());
  if (overlap != nullptr) *overlap = fraction_within;
  const Eigen::Isometry3d correction = T_target_source->inverse() * pose;
  if (fraction_within < config.min_overlap ||
      correction.translation().norm() > config.max_correction_m ||
      AngleDeg(correction.linear()) > config.max_correction_deg) {
    return false;
  }
  if (information != nullptr) {
    const Eigen::Vector3d centre = pose * centre_S;
    const NormalEquations at_optimum =
        Linearize(target, normals, tree, source, pose, centre, config.icp_last_max_distance_m,
                  config.point_sigma_m);
    *information = AlignmentInformation(
        at_optimum.H / (config.point_sigma_m * config.point_sigma_m), centre, radius_m,
        pose.translation(), config.information);
  }
  *T_target_source = pose;
  return true;
}

std::vector<PoseGraphEdge> ObjectConstraints(const std::vector<const MapObject*>& objects,
                                             const KeyframeAnchorLookup& anchor_of,
                                             const ObjectConstraintConfig& config,
                                             ObjectConstraintReport* report) {
  const auto start = std::chrono::steady_clock::now();
  *report = ObjectConstraintReport{};
  std::vector<PoseGraphEdge> edges;

  // Groups: labelled objects, joined when of one label and close (a duplicate).
  std::vector<const MapObject*> labelled;
  std::vector<int> labels;
  for (const MapObject* object : objects) {
    const int label = object->Label();
    if (label == kUnknownClassId || label < 0) continue;
    labelled.push_back(object);
    labels.push_back(label);
  }
  std::vector<int> parent(labelled.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) {
      i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    }
    return i;
  };
  for (std::size_t a = 0; a < labelled.size(); ++a) {
    for (std::size_t b = a + 1; b < labelled.size(); ++b) {
      if (labels[a] == labels[b] &&
          (labelled[a]->centroid_W - labelled[b]->centroid_W).norm() <=
              config.same_object_distance_m) {
        parent[static_cast<std::size_t>(root(static_cast<int>(a)))] = root(static_cast<int>(b));
      }
    }
  }

  struct View {
    int object = 0;  // index into labelled
    const ObjectObservation* observation = nullptr;
    KeyframeAnchor anchor;
    Eigen::Vector3d camera_W;
  };
  std::map<int, std::vector<View>> groups;
  for (std::size_t o = 0; o < labelled.size(); ++o) {
    for (const ObjectObservation& observation : labelled[o]->observations) {
      if (static_cast<int>(observation.segment_C.size()) < config.min_segment_points) continue;
      if (MedianDepth(observation.segment_C) > config.max_view_depth_m) continue;
      const std::optional<KeyframeAnchor> anchor = anchor_of(observation.keyframe_id);
      if (!anchor) continue;
      groups[root(static_cast<int>(o))].push_back(
          {static_cast<int>(o), &observation, *anchor,
           (anchor->T_W_node * anchor->T_node_C).translation()});
    }
  }

  for (const auto& [group, views] : groups) {
    struct Pair {
      bool across_objects;
      std::size_t smaller;
      std::size_t a, b;
    };
    std::vector<Pair> pairs;
    for (std::size_t a = 0; a < views.size(); ++a) {
      for (std::size_t b = a + 1; b < views.size(); ++b) {
        if (views[a].anchor.node == views[b].anchor.node ||
            (views[a].camera_W - views[b].camera_W).norm() < config.min_camera_separation_m) {
          continue;
        }
        pairs.push_back({views[a].object != views[b].object,
                         std::min(views[a].observation->segment_C.size(),
                                  views[b].observation->segment_C.size()),
                         a, b});
      }
    }
    if (pairs.empty()) continue;
    ++report->groups;
    // Views of two duplicates first (what the constraint is most needed for), then the largest.
    std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
      if (x.across_objects != y.across_objects) return x.across_objects;
      if (x.smaller != y.smaller) return x.smaller > y.smaller;
      return std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b);
    });
    std::vector<int> uses(views.size(), 0);
    int aligned = 0;
    for (const Pair& pair : pairs) {
      if (aligned >= config.max_pairs_per_object) break;
      if (uses[pair.a] >= 2 || uses[pair.b] >= 2) continue;
      ++uses[pair.a];
      ++uses[pair.b];
      ++aligned;
      // The larger view is the target: normals come from it.
      const bool a_larger = views[pair.a].observation->segment_C.size() >=
                            views[pair.b].observation->segment_C.size();
      const View& target = views[a_larger ? pair.a : pair.b];
      const View& source = views[a_larger ? pair.b : pair.a];
      const auto in_node = [](const View& view) {
        std::vector<Eigen::Vector3f> points;
        points.reserve(view.observation->segment_C.size());
        const Eigen::Isometry3f T = view.anchor.T_node_C.cast<float>();
        for (const Eigen::Vector3f& p : view.observation->segment_C.points) points.push_back(T * p);
        return points;
      };
      Eigen::Isometry3d T_target_source = target.anchor.T_W_node.inverse() * source.anchor.T_W_node;
      Eigen::Matrix<double, 6, 6> information;
      ++report->pairs_tried;
      if (!AlignSegments(in_node(target), in_node(source), config, &T_target_source, &information,
                         nullptr)) {
        continue;
      }
      PoseGraphEdge edge;
      edge.from = target.anchor.node;
      edge.to = source.anchor.node;
      edge.T_from_to = T_target_source;
      edge.information = information;
      edge.loop = true;
      edges.push_back(edge);
      ++report->constraints;
    }
  }
  report->ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return edges;
}

}  // namespace objmap
