// AlignDepth on depth images ray-cast from known scenes: a corner of a room with a box (every
// direction constrained) seen from two known poses, and a single wall (three directions free).

#include "odometry/depth_alignment.h"
#include "posegraph/pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace objmap {
namespace {

constexpr double kDegPerRad = 57.29577951308232;

struct Plane {
  Eigen::Vector3d normal;  // unit
  double offset;           // points x with normal.x = offset
};

// Depth of the nearest plane along each pixel's ray, for a camera at T_W_C; an axis-aligned box
// [box_min, box_max] is drawn too when box_max > box_min. Gaussian noise of sigma_m.
DepthImage RayCast(const std::vector<Plane>& planes, const Eigen::Vector3d& box_min,
                   const Eigen::Vector3d& box_max, const CameraIntrinsics& K,
                   const Eigen::Isometry3d& T_W_C, double sigma_m, unsigned seed) {
  DepthImage depth;
  depth.width = K.width;
  depth.height = K.height;
  depth.depth_m.assign(static_cast<std::size_t>(K.width) * K.height, 0.f);
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  const Eigen::Vector3d origin = T_W_C.translation();
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_C((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);  // z = 1
      const Eigen::Vector3d ray_W = T_W_C.linear() * ray_C;
      double best = std::numeric_limits<double>::infinity();
      for (const Plane& plane : planes) {
        const double along = plane.normal.dot(ray_W);
        if (std::abs(along) < 1e-9) continue;
        const double s = (plane.offset - plane.normal.dot(origin)) / along;
        if (s > 0.0) best = std::min(best, s);
      }
      if ((box_max - box_min).minCoeff() > 0.0) {  // slab test
        double enter = 0.0, leave = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a) {
          if (std::abs(ray_W(a)) < 1e-12) {
            if (origin(a) < box_min(a) || origin(a) > box_max(a)) leave = -1.0;
            continue;
          }
          double t0 = (box_min(a) - origin(a)) / ray_W(a), t1 = (box_max(a) - origin(a)) / ray_W(a);
          if (t0 > t1) std::swap(t0, t1);
          enter = std::max(enter, t0);
          leave = std::min(leave, t1);
        }
        if (enter <= leave && enter > 0.0) best = std::min(best, enter);
      }
      // Along a ray of z = 1 in the camera, the parameter is the depth.
      if (std::isfinite(best) && best < 10.0) {
        depth.depth_m[static_cast<std::size_t>(v) * K.width + u] =
            static_cast<float>(best + noise(random));
      }
    }
  }
  return depth;
}

Eigen::Isometry3d Pose(const Eigen::Vector3d& position, const Eigen::Vector3d& look_at) {
  // Camera z towards look_at, y roughly down (world z up).
  const Eigen::Vector3d z = (look_at - position).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = position;
  return T;
}

std::vector<Plane> RoomCorner() {
  return {{Eigen::Vector3d::UnitX(), 2.0}, {Eigen::Vector3d::UnitY(), 2.0},
          {Eigen::Vector3d::UnitZ(), 0.0}};  // two walls and the floor
}

struct Levels {
  DepthGrid coarse, fine;
};

Levels Grids(const DepthImage& depth, const CameraIntrinsics& K) {
  return {MakeDepthGrid(depth, K, 8, 6.0), MakeDepthGrid(depth, K, 4, 6.0)};
}

bool Align(const Levels& model, const Levels& frame, Eigen::Isometry3d* T,
           DepthAlignmentReport* report) {
  return AlignDepth({&model.coarse, &model.fine}, {&frame.coarse, &frame.fine},
                    {{10, 0.08, 0.03}, {20, 0.03, 0.01}}, 100, T, report);
}

TEST(DepthGrid, CellsAcrossADepthEdgeHaveNoPointAndNormalsFaceTheCamera) {
  const CameraIntrinsics K;
  DepthImage depth;
  depth.width = K.width;
  depth.height = K.height;
  // Left half at 1 m, right half at 2 m: the cells straddling column 320 +- 2 mix both.
  depth.depth_m.assign(static_cast<std::size_t>(K.width) * K.height, 1.f);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 322; u < K.width; ++u) depth.depth_m[static_cast<std::size_t>(v) * K.width + u] = 2.f;
  }
  const DepthGrid grid = MakeDepthGrid(depth, K, 8, 6.0);
  ASSERT_EQ(grid.width, 80);
  ASSERT_EQ(grid.height, 60);
  EXPECT_TRUE(std::isnan(grid.points[30 * 80 + 40].x())) << "cell 40 holds 1 m and 2 m";
  const Eigen::Vector3f& left = grid.points[30 * 80 + 20];
  ASSERT_FALSE(std::isnan(left.x()));
  EXPECT_NEAR(left.z(), 1.0f, 1e-5f);
  // The cell's centre pixel back-projects to the cell's point.
  EXPECT_NEAR(left.x(), (20 * 8 + 3.5 - K.cx) / K.fx, 1e-5);
  const Eigen::Vector3f& normal = grid.normals[30 * 80 + 20];
  ASSERT_FALSE(std::isnan(normal.x()));
  EXPECT_NEAR(normal.z(), -1.0f, 1e-4f);
  // Beside the edge the neighbours lie on the other surface: no normal.
  EXPECT_TRUE(std::isnan(grid.normals[30 * 80 + 41].x()));
}

TEST(DepthGrid, ANoisyFarWallKeepsItsCellsAndAFewPixelsOfAnotherSurfaceDoNotDropOne) {
  const CameraIntrinsics K;
  // A wall 3 m ahead with a structured-light sensor's noise there (sigma 1.55 cm): the range of
  // a cell's 64 depths is about 5 sigma, beyond 1 cm + 2 %, but its middle 80 % keep within.
  const DepthImage wall =
      RayCast({{Eigen::Vector3d::UnitZ(), 3.0}}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
              K, Eigen::Isometry3d::Identity(), 0.0015 * 9.0 + 0.002, 7);
  const DepthGrid grid = MakeDepthGrid(wall, K, 8, 4.0);
  int with_point = 0, with_normal = 0;
  double error_sum = 0.0;
  for (std::size_t c = 0; c < grid.points.size(); ++c) {
    if (std::isnan(grid.points[c].x())) continue;
    ++with_point;
    error_sum += std::abs(grid.points[c].z() - 3.0);
    with_normal += !std::isnan(grid.normals[c].x());
  }
  const auto cells = static_cast<int>(grid.points.size());
  EXPECT_GT(with_point, cells * 9 / 10);
  EXPECT_GT(with_normal, cells * 8 / 10);
  ASSERT_GT(with_point, 0);
  EXPECT_LT(error_sum / with_point, 0.005) << "a cell's point is the mean of its middle depths";

  // A 1 m cell with 2 x 2 of its 64 pixels on a surface at 2 m (a rim): the point stays at 1 m.
  DepthImage depth;
  depth.width = K.width;
  depth.height = K.height;
  depth.depth_m.assign(static_cast<std::size_t>(K.width) * K.height, 1.f);
  for (int v = 240; v < 242; ++v) {
    for (int u = 160; u < 162; ++u) depth.depth_m[static_cast<std::size_t>(v) * K.width + u] = 2.f;
  }
  const DepthGrid rimmed = MakeDepthGrid(depth, K, 8, 4.0);
  const Eigen::Vector3f& cell = rimmed.points[30 * 80 + 20];
  ASSERT_FALSE(std::isnan(cell.x()));
  EXPECT_NEAR(cell.z(), 1.0f, 1e-5f);
}

TEST(AlignDepth, RecoversAKnownMotionInAConstrainedScene) {
  const CameraIntrinsics K;
  const std::vector<Plane> room = RoomCorner();
  const Eigen::Vector3d box_min(0.6, 0.9, 0.0), box_max(1.0, 1.3, 0.5);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Eigen::Isometry3d T_W_model = Pose({-1.0, -1.2, 1.3}, {1.2, 1.0, 0.2});
    // The frame moved by 10 cm and 8 degrees; the start is off by 1.5-3 cm and 1 degree, as a
    // feature (PnP) pose can be.
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
    motion.linear() = Eigen::AngleAxisd(8.0 / kDegPerRad, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())
                          .toRotationMatrix();
    motion.translation() = Eigen::Vector3d(0.06, -0.07, 0.04);
    Eigen::Isometry3d start_error = Eigen::Isometry3d::Identity();
    start_error.linear() =
        Eigen::AngleAxisd(1.0 / kDegPerRad, Eigen::Vector3d(1.0, -0.5, 0.3 * seed).normalized())
            .toRotationMatrix();
    start_error.translation() = Eigen::Vector3d(0.01, 0.01 * seed, -0.01);
    const Eigen::Isometry3d T_W_frame = T_W_model * motion;
    const Levels model = Grids(RayCast(room, box_min, box_max, K, T_W_model, 0.002, seed), K);
    const Levels frame = Grids(RayCast(room, box_min, box_max, K, T_W_frame, 0.002, seed + 10), K);
    Eigen::Isometry3d T_model_frame = motion * start_error;
    DepthAlignmentReport report;
    ASSERT_TRUE(Align(model, frame, &T_model_frame, &report)) << "seed " << seed;
    const Eigen::Isometry3d error = motion.inverse() * T_model_frame;
    EXPECT_LT(error.translation().norm(), 0.002) << "seed " << seed;
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle() * kDegPerRad, 0.1) << "seed " << seed;
    EXPECT_GT(report.correspondences, 5000);
    EXPECT_LT(report.rmse_m, 0.005);
    EXPECT_GT(report.conditioning, 1e-4);
  }
}

TEST(AlignDepth, ASingleWallLeavesDirectionsFreeAndSaysSo) {
  const CameraIntrinsics K;
  const std::vector<Plane> wall = {{Eigen::Vector3d::UnitX(), 2.0}};
  const Eigen::Isometry3d T_W_model = Pose({0.0, 0.0, 1.0}, {2.0, 0.0, 1.0});
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.translation() = Eigen::Vector3d(0.02, 0.0, 0.03);  // sideways and towards the wall
  const Levels model = Grids(RayCast(wall, {}, {}, K, T_W_model, 0.0, 1), K);
  const Levels frame = Grids(RayCast(wall, {}, {}, K, T_W_model * motion, 0.0, 2), K);
  Eigen::Isometry3d T_model_frame = Eigen::Isometry3d::Identity();
  DepthAlignmentReport report;
  ASSERT_TRUE(Align(model, frame, &T_model_frame, &report));
  // Towards the wall is measured; sideways along it is not.
  EXPECT_NEAR(T_model_frame.translation().z(), 0.03, 0.002);
  EXPECT_LT(report.conditioning, 1e-6);
  // As a pose-graph edge: the floor's information towards the wall, next to none along it.
  const AlignmentInformationConfig floor;
  const Eigen::Matrix<double, 6, 6> information = AlignmentInformation(
      report.hessian, report.centre, report.radius_m, T_model_frame.translation(), floor);
  const double floor_m = 1.0 / (floor.floor_sigma_m * floor.floor_sigma_m);
  EXPECT_NEAR(information(2, 2), floor_m, 0.1 * floor_m);
  EXPECT_LT(information(0, 0), 0.01 * floor_m);
  EXPECT_LT(information(1, 1), 0.01 * floor_m);
}

TEST(AlignDepth, TooFewCorrespondencesLeaveThePoseAlone) {
  const CameraIntrinsics K;
  DepthImage empty;
  empty.width = K.width;
  empty.height = K.height;
  empty.depth_m.assign(static_cast<std::size_t>(K.width) * K.height, 0.f);
  const Levels model = Grids(RayCast(RoomCorner(), {}, {}, K, Pose({-1, -1, 1.2}, {1, 1, 0}), 0.0, 1), K);
  const Levels frame = Grids(empty, K);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  const Eigen::Isometry3d before = T;
  DepthAlignmentReport report;
  EXPECT_FALSE(Align(model, frame, &T, &report));
  EXPECT_EQ(report.correspondences, 0);
  EXPECT_TRUE(T.isApprox(before));
}

}  // namespace
}  // namespace objmap
