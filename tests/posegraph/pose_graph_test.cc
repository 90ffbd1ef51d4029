// PoseGraph on synthetic loops whose truth is known: drifted odometry closed by a true loop,
// the same with a wrong loop added (the robust loss must keep it from bending the map, and
// report it), and malformed edges.

#include "posegraph/pose_graph.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace objmap {
namespace {

// A camera going once around a 2 m x 1.5 m rectangle, a node every 10 cm, turning at corners.
std::vector<Eigen::Isometry3d> TrueLoop() {
  std::vector<Eigen::Isometry3d> poses;
  const double width = 2.0, depth = 1.5, step = 0.1;
  const Eigen::Vector2d corners[4] = {{0, 0}, {width, 0}, {width, depth}, {0, depth}};
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector2d a = corners[side], b = corners[(side + 1) % 4];
    const int steps = static_cast<int>(std::round((b - a).norm() / step));
    const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
    for (int k = 0; k < steps; ++k) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      const Eigen::Vector2d xy = a + (b - a) * (static_cast<double>(k) / steps);
      T.translation() = Eigen::Vector3d(xy.x(), xy.y(), 1.2 + 0.05 * std::sin(0.3 * k));
      T.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).matrix();
      poses.push_back(T);
    }
  }
  return poses;
}

Eigen::Matrix<double, 6, 6> Information(double sigma_m, double sigma_rad) {
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

// Root mean square position error of the graph's poses against the truth (the first node is
// fixed at its true pose, so no alignment is needed).
double PositionRmse(const PoseGraph& graph, const std::vector<Eigen::Isometry3d>& truth) {
  double sum = 0.0;
  for (const auto& [id, T] : graph.poses()) {
    sum += (T.translation() - truth[static_cast<std::size_t>(id)].translation()).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(graph.poses().size()));
}

// The loop's odometry: true steps with noise and a yaw bias of 0.4 degrees per step (drift),
// chained into the initial poses.
PoseGraph DriftedGraph(const std::vector<Eigen::Isometry3d>& truth, unsigned seed,
                       const PoseGraphConfig& config) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  PoseGraph graph(config);
  graph.AddNode(0, truth[0]);
  Eigen::Isometry3d chained = truth[0];
  std::string why;
  for (std::size_t i = 1; i < truth.size(); ++i) {
    Eigen::Isometry3d step = truth[i - 1].inverse() * truth[i];
    step.translation() += 0.003 * Eigen::Vector3d(noise(random), noise(random), noise(random));
    step.rotate(Eigen::AngleAxisd(0.007 + 0.002 * noise(random), Eigen::Vector3d::UnitZ()));
    chained = chained * step;
    graph.AddNode(static_cast<int>(i), chained);
    PoseGraphEdge edge;
    edge.from = static_cast<int>(i - 1);
    edge.to = static_cast<int>(i);
    edge.T_from_to = step;
    edge.information = Information(0.005, 0.01);
    EXPECT_TRUE(graph.AddEdge(edge, &why)) << why;
  }
  return graph;
}

PoseGraphEdge Loop(const std::vector<Eigen::Isometry3d>& truth, int from, int to) {
  PoseGraphEdge edge;
  edge.from = from;
  edge.to = to;
  edge.T_from_to = truth[static_cast<std::size_t>(from)].inverse() * truth[static_cast<std::size_t>(to)];
  edge.information = Information(0.01, 0.01);
  edge.loop = true;
  return edge;
}

TEST(PoseGraph, ATrueLoopRemovesTheDrift) {
  const std::vector<Eigen::Isometry3d> truth = TrueLoop();
  const int last = static_cast<int>(truth.size()) - 1;
  for (unsigned seed : {1u, 2u, 3u}) {
    PoseGraph graph = DriftedGraph(truth, seed, PoseGraphConfig{});
    const double before = PositionRmse(graph, truth);
    std::string why;
    ASSERT_TRUE(graph.AddEdge(Loop(truth, last, 0), &why)) << why;
    PoseGraphReport report;
    ASSERT_TRUE(graph.Optimize(&report, &why)) << why;
    const double after = PositionRmse(graph, truth);
    EXPECT_GT(before, 0.15) << "seed " << seed << ": the drift this test corrects";
    EXPECT_LT(after, 0.03) << "seed " << seed << " (before " << before << ")";
    EXPECT_TRUE(report.rejected_loops.empty());
    EXPECT_LT(report.final_cost, report.initial_cost);
    EXPECT_TRUE(graph.poses().at(0).isApprox(truth[0])) << "the first node is the gauge";
  }
}

TEST(PoseGraph, AWrongLoopIsOutweighedAndReported) {
  const std::vector<Eigen::Isometry3d> truth = TrueLoop();
  const int last = static_cast<int>(truth.size()) - 1;
  // Nodes 10 and 45 are on opposite sides, about 1.5 m apart: a loop claiming they are 5 cm
  // apart, as a repeated texture on two cupboards could.
  PoseGraphEdge wrong = Loop(truth, 10, 45);
  wrong.T_from_to = Eigen::Isometry3d::Identity();
  wrong.T_from_to.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
  for (unsigned seed : {1u, 2u, 3u}) {
    std::string why;
    PoseGraph right_only = DriftedGraph(truth, seed, PoseGraphConfig{});
    ASSERT_TRUE(right_only.AddEdge(Loop(truth, last, 0), &why));
    PoseGraphReport report;
    ASSERT_TRUE(right_only.Optimize(&report, &why)) << why;
    const double right_rmse = PositionRmse(right_only, truth);

    PoseGraph robust = DriftedGraph(truth, seed, PoseGraphConfig{});
    ASSERT_TRUE(robust.AddEdge(Loop(truth, last, 0), &why));
    ASSERT_TRUE(robust.AddEdge(wrong, &why));
    ASSERT_TRUE(robust.Optimize(&report, &why)) << why;
    EXPECT_LT(PositionRmse(robust, truth), right_rmse + 0.02) << "seed " << seed;
    ASSERT_EQ(report.rejected_loops.size(), 1u) << "seed " << seed;
    EXPECT_EQ(robust.edges()[static_cast<std::size_t>(report.rejected_loops[0])].from, 10);

    // The robust loss alone (no loop dropped) already keeps the map close.
    PoseGraphConfig loss_only;
    loss_only.loop_rejection_chi2 = 1e12;
    PoseGraph damped = DriftedGraph(truth, seed, loss_only);
    ASSERT_TRUE(damped.AddEdge(Loop(truth, last, 0), &why));
    ASSERT_TRUE(damped.AddEdge(wrong, &why));
    ASSERT_TRUE(damped.Optimize(&report, &why)) << why;
    EXPECT_LT(PositionRmse(damped, truth), right_rmse + 0.05) << "seed " << seed;

    // With neither (a quadratic loss, nothing dropped) the wrong loop bends the map.
    PoseGraphConfig quadratic;
    quadratic.loop_loss_scale = 1e6;
    quadratic.loop_rejection_chi2 = 1e12;
    PoseGraph bent = DriftedGraph(truth, seed, quadratic);
    ASSERT_TRUE(bent.AddEdge(Loop(truth, last, 0), &why));
    ASSERT_TRUE(bent.AddEdge(wrong, &why));
    ASSERT_TRUE(bent.Optimize(&report, &why)) << why;
    EXPECT_GT(PositionRmse(bent, truth), 0.2) << "seed " << seed;
  }
}

TEST(PoseGraph, MalformedEdgesAreRefused) {
  PoseGraph graph;
  graph.AddNode(0, Eigen::Isometry3d::Identity());
  graph.AddNode(1, Eigen::Isometry3d::Identity());
  PoseGraphEdge edge;
  edge.from = 0;
  edge.to = 7;
  std::string why;
  EXPECT_FALSE(graph.AddEdge(edge, &why));
  EXPECT_NE(why.find("unknown node"), std::string::npos) << why;
  edge.to = 1;
  edge.information(0, 0) = -1.0;
  EXPECT_FALSE(graph.AddEdge(edge, &why));
  EXPECT_NE(why.find("positive definite"), std::string::npos) << why;
  PoseGraphReport report;
  EXPECT_FALSE(graph.Optimize(&report, &why));
}

// The whitened point-to-plane Hessian of `points` with `normals` (sigma 1 mm), increments turning
// about `centre`.
Eigen::Matrix<double, 6, 6> PlaneHessian(const std::vector<Eigen::Vector3d>& points,
                                         const std::vector<Eigen::Vector3d>& normals,
                                         const Eigen::Vector3d& centre) {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    Eigen::Matrix<double, 6, 1> J;
    J << normals[i], (points[i] - centre).cross(normals[i]);
    H += J * J.transpose() / (0.001 * 0.001);
  }
  return H;
}

TEST(AlignmentInformation, AWallFixesItsNormalAndTiltsAndLeavesTheRestFree) {
  // A 2 m x 2 m wall at z = 2 seen from the origin, a point every 5 cm; normals slightly noisy.
  std::mt19937 random(3);
  std::normal_distribution<double> tilt(0.0, 0.03);
  std::vector<Eigen::Vector3d> points, normals;
  for (double x = -1.0; x <= 1.0; x += 0.05) {
    for (double y = -1.0; y <= 1.0; y += 0.05) {
      points.emplace_back(x, y, 2.0);
      normals.push_back(Eigen::Vector3d(tilt(random), tilt(random), -1.0).normalized());
    }
  }
  const Eigen::Vector3d centre(0.0, 0.0, 2.0);
  const Eigen::Vector3d to_origin(0.3, 0.0, 0.0);  // the other camera, 30 cm to the side
  const AlignmentInformationConfig config;
  const Eigen::Matrix<double, 6, 6> information =
      AlignmentInformation(PlaneHessian(points, normals, centre), centre, 0.8, to_origin, config);
  const double floor_m = 1.0 / (config.floor_sigma_m * config.floor_sigma_m);
  // Along the normal: the floor; across the wall: next to nothing (the prior's 1 / m^2).
  EXPECT_NEAR(information(2, 2), floor_m, 0.05 * floor_m);
  EXPECT_LT(information(0, 0), 10.0);
  EXPECT_LT(information(1, 1), 10.0);
  // Turning about the wall's normal (z) is free; tilting it is not.
  const double floor_rad = 1.0 / std::pow(config.floor_sigma_deg * 0.017453292519943295, 2);
  EXPECT_LT(information(5, 5), 0.01 * floor_rad);
  EXPECT_GT(information(3, 3), 0.5 * floor_rad);
  EXPECT_TRUE(information.isApprox(information.transpose()));
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> cholesky(information);
  EXPECT_EQ(cholesky.info(), Eigen::Success);

  // A corner of three walls fixes everything: the floor in every direction.
  std::vector<Eigen::Vector3d> corner_points = points, corner_normals = normals;
  for (double a = -1.0; a <= 1.0; a += 0.05) {
    for (double b = 0.0; b <= 2.0; b += 0.05) {
      corner_points.emplace_back(-1.0, a, b);
      corner_normals.emplace_back(1.0, 0.0, 0.0);
      corner_points.emplace_back(a, -1.0, b);
      corner_normals.emplace_back(0.0, 1.0, 0.0);
    }
  }
  const Eigen::Matrix<double, 6, 6> corner = AlignmentInformation(
      PlaneHessian(corner_points, corner_normals, centre), centre, 1.0, to_origin, config);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(corner(i, i), floor_m, 0.1 * floor_m) << i;
  for (int i = 3; i < 6; ++i) EXPECT_GT(corner(i, i), 0.5 * floor_rad) << i;
}

}  // namespace
}  // namespace objmap
