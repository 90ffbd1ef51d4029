#include "sim/revisit_geometry.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

// An upward horizontal face of the structure; a box's top face is two triangles spanning the
// same rectangle.
struct UpwardFace {
  Eigen::Vector2d min_xy, max_xy;
  double z = 0.0;
  double Area() const { return (max_xy - min_xy).prod(); }
};

std::vector<UpwardFace> UpwardFaces(const TriangleMesh& mesh) {
  std::vector<UpwardFace> faces;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() < 1e-9 || normal.z() < 0.999 * normal.norm()) continue;
    UpwardFace face;
    face.min_xy = a.head<2>().cwiseMin(b.head<2>()).cwiseMin(c.head<2>());
    face.max_xy = a.head<2>().cwiseMax(b.head<2>()).cwiseMax(c.head<2>());
    face.z = a.z();
    const bool known = std::any_of(faces.begin(), faces.end(), [&](const UpwardFace& f) {
      return std::abs(f.z - face.z) < 1e-4 && (f.min_xy - face.min_xy).norm() < 1e-4 &&
             (f.max_xy - face.max_xy).norm() < 1e-4;
    });
    if (!known) faces.push_back(face);
  }
  return faces;
}

// The point the cameras of a trajectory look at: the least-squares meeting point of their
// optical axes. False when the axes are (nearly) parallel.
bool LookedAtPoint(const std::vector<Eigen::Isometry3d>& trajectory, Eigen::Vector3d* target) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& T_W_C : trajectory) {
    const Eigen::Vector3d d = T_W_C.linear().col(2).normalized();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += across;
    b += across * T_W_C.translation();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(A);
  if (eigen.eigenvalues().minCoeff() < 1e-3 * static_cast<double>(trajectory.size())) {
    return false;
  }
  *target = A.ldlt().solve(b);
  return true;
}

}  // namespace

WorldBox ObjectWorldBox(const SceneObject& object) {
  Eigen::Vector3f min, max;
  object.mesh.Bounds(&min, &max);
  WorldBox box{Eigen::Vector3d::Constant(1e30), Eigen::Vector3d::Constant(-1e30)};
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? max.x() : min.x(), (i & 2) ? max.y() : min.y(),
                                 (i & 4) ? max.z() : min.z());
    const Eigen::Vector3d p_W = object.T_W_O * corner;
    box.min = box.min.cwiseMin(p_W);
    box.max = box.max.cwiseMax(p_W);
  }
  return box;
}

Eigen::Vector3d ObjectBoxCentre(const SceneObject& object) {
  Eigen::Vector3f min, max;
  object.mesh.Bounds(&min, &max);
  return object.T_W_O * (0.5f * (min + max)).cast<double>();
}

bool BoxesClash(const WorldBox& a, const WorldBox& b, double gap_m, double touch_m) {
  for (int axis = 0; axis < 2; ++axis) {
    if (a.min[axis] >= b.max[axis] + gap_m || b.min[axis] >= a.max[axis] + gap_m) return false;
  }
  return a.min.z() < b.max.z() - touch_m && b.min.z() < a.max.z() - touch_m;
}

bool FindRoomLayout(const Scene& scene, RoomLayout* layout, std::string* why) {
  *layout = RoomLayout{};
  const std::vector<UpwardFace> faces = UpwardFaces(scene.structure);
  if (faces.empty()) {
    *why = "the scene's structure has no floor";
    return false;
  }
  const UpwardFace floor =
      *std::min_element(faces.begin(), faces.end(), [](const UpwardFace& a, const UpwardFace& b) {
        return a.z < b.z - 1e-4 || (std::abs(a.z - b.z) <= 1e-4 && a.Area() > b.Area());
      });
  layout->supports.push_back({floor.min_xy, floor.max_xy, floor.z, /*floor=*/true, 0});
  for (const UpwardFace& face : faces) {
    // The ceiling's top spans the room; everything else above the floor stands on it.
    if (face.z <= floor.z + 0.01 || face.Area() > 0.5 * floor.Area()) continue;
    layout->obstacles.push_back({Eigen::Vector3d(face.min_xy.x(), face.min_xy.y(), floor.z),
                                 Eigen::Vector3d(face.max_xy.x(), face.max_xy.y(), face.z)});
    const Eigen::Vector2d size = face.max_xy - face.min_xy;
    if (face.z >= floor.z + 0.3 && face.z <= floor.z + 1.3 && size.minCoeff() >= 0.2) {
      layout->supports.push_back({face.min_xy, face.max_xy, face.z, /*floor=*/false, 0});
    }
  }
  for (const SceneObject& object : scene.objects) {
    if (std::string(CocoClassName(object.class_id)) != "dining table") continue;
    const WorldBox box = ObjectWorldBox(object);
    layout->supports.push_back(
        {box.min.head<2>(), box.max.head<2>(), box.max.z(), /*floor=*/false, object.id});
  }
  return true;
}

int SupportUnder(const RoomLayout& layout, const WorldBox& box) {
  const Eigen::Vector2d centre = 0.5 * (box.min + box.max).head<2>();
  int best = -1;
  for (std::size_t i = 0; i < layout.supports.size(); ++i) {
    const SupportSurface& s = layout.supports[i];
    const bool over = (centre.array() >= s.min_xy.array() - 0.01).all() &&
                      (centre.array() <= s.max_xy.array() + 0.01).all();
    if (!over || s.z > box.min.z() + 0.02) continue;
    if (best < 0 || s.z > layout.supports[static_cast<std::size_t>(best)].z) {
      best = static_cast<int>(i);
    }
  }
  return best;
}

int FramesInView(const Eigen::Vector3d& point_W, const std::vector<Eigen::Isometry3d>& trajectory,
                 const CameraIntrinsics& K, double max_m) {
  int frames = 0;
  for (const Eigen::Isometry3d& T_W_C : trajectory) {
    const Eigen::Vector3d p = T_W_C.inverse() * point_W;
    if (p.z() < 0.05 || p.norm() > max_m) continue;
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    frames += u >= 0.0 && u < K.width && v >= 0.0 && v < K.height;
  }
  return frames;
}

std::vector<Eigen::Isometry3d> RevisitTrajectory(const std::vector<Eigen::Isometry3d>& first,
                                                 const SupportSurface& floor, int frames,
                                                 Random* random) {
  std::vector<Eigen::Isometry3d> poses;
  if (first.empty() || frames < 1) return poses;
  const Eigen::Isometry3d& middle = first[first.size() / 2];
  Eigen::Vector3d target;
  if (!LookedAtPoint(first, &target)) {
    target = middle.translation() + 1.7 * middle.linear().col(2);
  }
  double radius = 0.0, above = 0.0, path_m = 0.0;
  for (std::size_t k = 0; k < first.size(); ++k) {
    const Eigen::Vector3d offset = first[k].translation() - target;
    radius += offset.head<2>().norm() / static_cast<double>(first.size());
    above += offset.z() / static_cast<double>(first.size());
    if (k > 0) path_m += (first[k].translation() - first[k - 1].translation()).norm();
  }
  radius = std::max(radius, 0.5);
  const Eigen::Vector3d from_target = middle.translation() - target;
  const double middle_azimuth = std::atan2(from_target.y(), from_target.x());
  // Farther and higher than the first sweep's middle: the same objects, seen from elsewhere.
  double new_radius = radius * random->Uniform(1.1, 1.2);
  const double height = target.z() + std::max(above, 0.3) + random->Uniform(0.1, 0.2);
  const double side = random->Uniform() < 0.5 ? -1.0 : 1.0;
  auto eye_at = [&](double s, double r, double swing) {
    // Out to one side for the first third, then across to the other.
    const double p = 3.0 * s;
    const double azimuth = middle_azimuth + side * swing * (p <= 1.0 ? -p : p - 2.0);
    return Eigen::Vector3d(target.x() + r * std::cos(azimuth), target.y() + r * std::sin(azimuth),
                           height + 0.04 * std::sin(2.0 * M_PI * s));
  };
  auto inside = [&](const Eigen::Vector3d& eye) {
    return (eye.head<2>().array() >= floor.min_xy.array() + 0.3).all() &&
           (eye.head<2>().array() <= floor.max_xy.array() - 0.3).all();
  };
  for (int attempt = 0; attempt < 8; ++attempt) {
    // Three swings as long, together, as the first sweep.
    const double swing = std::clamp(path_m / (3.0 * new_radius), 0.4, 0.7);
    poses.clear();
    bool all_inside = true;
    for (int i = 0; i < frames; ++i) {
      const double s = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.0;
      const Eigen::Vector3d eye = eye_at(s, new_radius, swing);
      all_inside = all_inside && inside(eye);
      poses.push_back(testing::LookAt(eye, target));
    }
    if (all_inside) break;
    new_radius = std::max(0.9 * radius, 0.95 * new_radius);
  }
  return poses;
}

std::vector<Eigen::Isometry3d> PatrolTrajectory(const std::vector<Eigen::Isometry3d>& first,
                                                int frames, double offset_m, double offset_deg,
                                                Random* random) {
  std::vector<Eigen::Isometry3d> poses;
  if (first.empty() || frames < 1) return poses;
  // One slow wave per axis, with its own phase and about one period over the path.
  double phase[6], period[6];
  for (int axis = 0; axis < 6; ++axis) {
    phase[axis] = random->Uniform(0.0, 2.0 * M_PI);
    period[axis] = random->Uniform(0.7, 1.4);
  }
  auto wave = [&](int axis, double s) {
    return std::sin(2.0 * M_PI * s / period[axis] + phase[axis]);
  };
  const double offset_rad = offset_deg * M_PI / 180.0;
  for (int i = 0; i < frames; ++i) {
    const double s = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.0;
    // The pose of the first path at s, between its two nearest poses.
    const double at = s * static_cast<double>(first.size() - 1);
    const std::size_t k = std::min(static_cast<std::size_t>(at), first.size() - 1);
    const std::size_t next = std::min(k + 1, first.size() - 1);
    const double t = at - static_cast<double>(k);
    const Eigen::Quaterniond q_a(first[k].linear()), q_b(first[next].linear());
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = q_a.slerp(t, q_b).toRotationMatrix();
    pose.translation() = (1.0 - t) * first[k].translation() + t * first[next].translation();
    pose.translation() += offset_m * Eigen::Vector3d(wave(0, s), wave(1, s), 0.5 * wave(2, s));
    // Turned a little about the world's vertical and the camera's own axes.
    pose.linear() = Eigen::AngleAxisd(offset_rad * wave(3, s), Eigen::Vector3d::UnitZ()) *
                    pose.linear() *
                    Eigen::AngleAxisd(0.5 * offset_rad * wave(4, s), Eigen::Vector3d::UnitX()) *
                    Eigen::AngleAxisd(0.5 * offset_rad * wave(5, s), Eigen::Vector3d::UnitY());
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace objmap::sim
