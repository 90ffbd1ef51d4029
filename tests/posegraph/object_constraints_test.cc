// Object views aligned into pose-graph constraints: a box seen from two cameras far apart gives
// their relative pose back from a drifted guess; a flat screen fixes only its normal and tilt
// (the information matrix says so); views of different things are refused; and from a map's
// objects (one mapped twice through drift) the constraints tie the right nodes.

#include "posegraph/object_constraints.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "types/coco_classes.h"

namespace objmap {
namespace {

constexpr double kRadPerDeg = 0.017453292519943295;
const Eigen::Vector3d kBoxCentre(0.0, 2.0, 0.8);
// Both cameras see the box's front (y-), top (z+) and left side (x-): three shared faces.
const Eigen::Vector3d kFirstCamera(-0.9, 1.2, 1.5);
const Eigen::Vector3d kSecondCamera(-0.3, 0.9, 1.1);

struct Surface {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
};

// The faces of an axis-aligned box centred at `centre`, a point every 5 mm.
Surface Box(const Eigen::Vector3d& centre, const Eigen::Vector3d& size) {
  Surface surface;
  const double step = 0.005;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side : {-1, 1}) {
      for (double a = -size[u] / 2; a <= size[u] / 2; a += step) {
        for (double b = -size[v] / 2; b <= size[v] / 2; b += step) {
          Eigen::Vector3d p = centre;
          p[axis] += side * size[axis] / 2;
          p[u] += a;
          p[v] += b;
          Eigen::Vector3d n = Eigen::Vector3d::Zero();
          n[axis] = side;
          surface.points.push_back(p);
          surface.normals.push_back(n);
        }
      }
    }
  }
  return surface;
}

// A flat screen in the plane y = centre.y (normal -y), a point every 5 mm.
Surface Screen(const Eigen::Vector3d& centre, double width, double height) {
  Surface surface;
  for (double a = -width / 2; a <= width / 2; a += 0.005) {
    for (double b = -height / 2; b <= height / 2; b += 0.005) {
      surface.points.push_back(centre + Eigen::Vector3d(a, 0.0, b));
      surface.normals.push_back(-Eigen::Vector3d::UnitY());
    }
  }
  return surface;
}

// A camera at `position` looking at `target` (z forward, y down).
Eigen::Isometry3d LookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - position).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << x, y, z;
  T.translation() = position;
  return T;
}

// The surface points the camera faces, in its frame, with depth noise along the ray.
std::vector<Eigen::Vector3f> View(const Surface& surface, const Eigen::Isometry3d& T_W_C,
                                  std::mt19937* random, double noise_m = 0.001) {
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    if (surface.normals[i].dot(T_W_C.translation() - surface.points[i]) <= 0.0) continue;
    Eigen::Vector3d p_C = T_W_C.inverse() * surface.points[i];
    p_C *= 1.0 + noise(*random) / p_C.norm();
    points.push_back(p_C.cast<float>());
  }
  return points;
}

Eigen::Isometry3d Perturbed(const Eigen::Isometry3d& T, std::mt19937* random, double metres,
                            double degrees) {
  std::normal_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(unit(*random), unit(*random), unit(*random)).normalized();
  const Eigen::Vector3d shift = Eigen::Vector3d(unit(*random), unit(*random), unit(*random)).normalized();
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(degrees * kRadPerDeg, axis).toRotationMatrix();
  delta.translation() = metres * shift;
  return delta * T;
}

double TranslationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}
double AngleErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd((a.inverse() * b).linear()).angle() / kRadPerDeg;
}

TEST(ObjectConstraints, TwoDistantViewsOfABoxGiveTheirRelativePoseBack) {
  const Surface box = Box({0.0, 2.0, 0.8}, {0.3, 0.2, 0.25});
  for (unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 random(seed);
    // Two cameras 0.8 m apart, both seeing the box's front, top and left side.
    const Eigen::Isometry3d T_W_a = LookAt(kFirstCamera, kBoxCentre);
    const Eigen::Isometry3d T_W_b = LookAt(kSecondCamera, kBoxCentre);
    const std::vector<Eigen::Vector3f> a = View(box, T_W_a, &random);
    const std::vector<Eigen::Vector3f> b = View(box, T_W_b, &random);
    const Eigen::Isometry3d truth = T_W_a.inverse() * T_W_b;
    Eigen::Isometry3d estimate = Perturbed(truth, &random, 0.03, 1.0);
    ASSERT_GT(TranslationError(estimate, truth), 0.01);
    Eigen::Matrix<double, 6, 6> information;
    double overlap = 0.0;
    ASSERT_TRUE(AlignSegments(a, b, ObjectConstraintConfig{}, &estimate, &information, &overlap))
        << "seed " << seed << ", overlap " << overlap;
    EXPECT_LT(TranslationError(estimate, truth), 0.004) << "seed " << seed;
    EXPECT_LT(AngleErrorDeg(estimate, truth), 0.3) << "seed " << seed;
    EXPECT_GT(overlap, 0.5);
    // Three faces fix every direction: the floor (1 cm, 0.5 deg) bounds the information.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(information);
    EXPECT_GT(eigen.eigenvalues()(0), 100.0) << "seed " << seed;
    EXPECT_LE(information.diagonal().head<3>().maxCoeff(), 1.0 / (0.01 * 0.01) + 1e-6);
  }
}

TEST(ObjectConstraints, AFlatScreenFixesItsNormalAndLeavesItsPlaneFree) {
  const Surface screen = Screen({0.0, 3.0, 1.5}, 0.6, 0.35);
  std::mt19937 random(7);
  const Eigen::Isometry3d T_W_a = LookAt({-0.8, 1.2, 1.3}, {0.0, 3.0, 1.5});
  const Eigen::Isometry3d T_W_b = LookAt({0.9, 1.0, 1.2}, {0.0, 3.0, 1.5});
  const std::vector<Eigen::Vector3f> a = View(screen, T_W_a, &random);
  const std::vector<Eigen::Vector3f> b = View(screen, T_W_b, &random);
  const Eigen::Isometry3d truth = T_W_a.inverse() * T_W_b;
  // The guess is off along the screen's normal (world y) by 4 cm.
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.translation() = T_W_a.inverse().linear() * Eigen::Vector3d(0.0, 0.04, 0.0);
  Eigen::Isometry3d estimate = offset * truth;
  Eigen::Matrix<double, 6, 6> information;
  ASSERT_TRUE(AlignSegments(a, b, ObjectConstraintConfig{}, &estimate, &information, nullptr));
  // The normal offset is gone (points of b land on a's plane).
  const Eigen::Vector3d normal_a = T_W_a.inverse().linear() * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d error_a = (estimate * truth.inverse()).translation();
  EXPECT_LT(std::abs(error_a.dot(normal_a)), 0.005);
  // Information along the normal (camera a's frame) is the floor's; in the plane next to none.
  const Eigen::Matrix3d translation_information = information.topLeftCorner<3, 3>();
  const Eigen::Vector3d in_plane = normal_a.cross(Eigen::Vector3d::UnitX()).normalized();
  const double along_normal = normal_a.dot(translation_information * normal_a);
  const double along_plane = in_plane.dot(translation_information * in_plane);
  EXPECT_GT(along_normal, 100.0 * along_plane)
      << "normal " << along_normal << ", plane " << along_plane;
}

TEST(ObjectConstraints, ViewsOfDifferentThingsAreRefused) {
  std::mt19937 random(11);
  const Eigen::Isometry3d T_W_a = LookAt(kFirstCamera, kBoxCentre);
  const Eigen::Isometry3d T_W_b = LookAt(kSecondCamera, kBoxCentre);
  // A box seen by a, a screen 12 cm behind it seen by b: nothing of b lies on a's surfaces.
  const std::vector<Eigen::Vector3f> a = View(Box({0.0, 2.0, 0.8}, {0.3, 0.2, 0.25}), T_W_a, &random);
  const std::vector<Eigen::Vector3f> b = View(Screen({0.0, 2.22, 0.8}, 0.5, 0.6), T_W_b, &random);
  Eigen::Isometry3d estimate = T_W_a.inverse() * T_W_b;
  const Eigen::Isometry3d before = estimate;
  double overlap = 1.0;
  EXPECT_FALSE(AlignSegments(a, b, ObjectConstraintConfig{}, &estimate, nullptr, &overlap));
  EXPECT_EQ(overlap, 0.0);
  EXPECT_TRUE(estimate.isApprox(before));
}

MapObject ObjectOf(ObjectId id, const std::vector<ObjectObservation>& observations,
                   const Eigen::Vector3f& centroid_W) {
  MapObject object;
  object.id = id;
  object.observations = observations;
  object.centroid_W = centroid_W;
  for (const ObjectObservation& observation : observations) {
    for (const auto& [c, score] : observation.class_scores) {
      object.accumulated_scores[static_cast<std::size_t>(c)] += score;
    }
  }
  return object;
}

ObjectObservation Observation(KeyframeId keyframe, int class_id,
                              const std::vector<Eigen::Vector3f>& points) {
  ObjectObservation observation;
  observation.keyframe_id = keyframe;
  observation.class_scores = {{class_id, 0.6f}};
  observation.segment_C.points = points;
  return observation;
}

TEST(ObjectConstraints, AnObjectMappedTwiceThroughDriftTiesTheNodesThatSawIt) {
  const int tv = CocoClassId("tv");
  const int cup = CocoClassId("cup");
  ASSERT_GE(tv, 0);
  const Surface box = Box({0.0, 2.0, 0.8}, {0.3, 0.2, 0.25});
  std::mt19937 random(5);
  // Keyframes 1 and 2 (nodes 10 and 20) saw the "tv" (a box, for shape) from far apart; the
  // drifted graph puts node 20 3 cm and 1 degree off, so the map holds the tv twice.
  const Eigen::Isometry3d T_W_1 = LookAt(kFirstCamera, kBoxCentre);
  const Eigen::Isometry3d T_W_2 = LookAt(kSecondCamera, kBoxCentre);
  const Eigen::Isometry3d drifted_2 = Perturbed(T_W_2, &random, 0.03, 1.0);
  // Each keyframe sits 5 cm ahead of its node (a tracked frame's offset).
  Eigen::Isometry3d T_node_C = Eigen::Isometry3d::Identity();
  T_node_C.translation() = Eigen::Vector3d(0.0, 0.0, 0.05);
  const std::vector<Eigen::Vector3f> view_1 = View(box, T_W_1, &random);
  const std::vector<Eigen::Vector3f> view_2 = View(box, T_W_2, &random);
  const MapObject first = ObjectOf(1, {Observation(1, tv, view_1)}, {0.0f, 2.0f, 0.8f});
  const MapObject second = ObjectOf(2, {Observation(2, tv, view_2)}, {0.03f, 1.98f, 0.82f});
  // A cup far away, seen once: nothing to pair it with.
  const MapObject lone = ObjectOf(3, {Observation(1, cup, view_1)}, {2.0f, 0.0f, 0.8f});
  const std::vector<const MapObject*> objects = {&first, &second, &lone};
  const auto anchor_of = [&](KeyframeId id) -> std::optional<KeyframeAnchor> {
    if (id == 1) return KeyframeAnchor{10, T_W_1 * T_node_C.inverse(), T_node_C};
    if (id == 2) return KeyframeAnchor{20, drifted_2 * T_node_C.inverse(), T_node_C};
    return std::nullopt;
  };
  ObjectConstraintReport report;
  const std::vector<PoseGraphEdge> edges =
      ObjectConstraints(objects, anchor_of, ObjectConstraintConfig{}, &report);
  ASSERT_EQ(edges.size(), 1u);
  EXPECT_EQ(report.groups, 1);
  EXPECT_EQ(report.constraints, 1);
  const PoseGraphEdge& edge = edges[0];
  EXPECT_TRUE(edge.loop);
  ASSERT_TRUE((edge.from == 10 && edge.to == 20) || (edge.from == 20 && edge.to == 10));
  const Eigen::Isometry3d T_W_node10 = T_W_1 * T_node_C.inverse();
  const Eigen::Isometry3d T_W_node20 = T_W_2 * T_node_C.inverse();
  const Eigen::Isometry3d truth = edge.from == 10 ? T_W_node10.inverse() * T_W_node20
                                                  : T_W_node20.inverse() * T_W_node10;
  EXPECT_LT(TranslationError(edge.T_from_to, truth), 0.005);
  EXPECT_LT(AngleErrorDeg(edge.T_from_to, truth), 0.3);

  // Cameras closer than min_camera_separation_m are left to odometry.
  ObjectConstraintConfig near;
  near.min_camera_separation_m = 5.0;
  EXPECT_TRUE(ObjectConstraints(objects, anchor_of, near, &report).empty());
  EXPECT_EQ(report.groups, 0);
}

TEST(ObjectConstraints, ConfigValidation) {
  std::string why;
  EXPECT_TRUE(ObjectConstraintConfig{}.IsValid(&why)) << why;
  ObjectConstraintConfig bad;
  bad.icp_last_max_distance_m = 0.1;  // above the first
  EXPECT_FALSE(bad.IsValid(&why));
  bad = {};
  bad.min_overlap = 0.0;
  EXPECT_FALSE(bad.IsValid(&why));
  bad = {};
  bad.information.floor_sigma_deg = -1.0;
  EXPECT_FALSE(bad.IsValid(&why));
}

}  // namespace
}  // namespace objmap
