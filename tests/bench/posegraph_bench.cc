// PoseGraph solve time against the number of keyframes: a random walk through a 4 m room (a
// keyframe every 10 cm, drifting odometry) with a loop edge back to an earlier keyframe every 20
// keyframes where the walk comes near one, as a loop detector would give. Reports the solve
// time and the position error before and after against the walk's truth.
//   posegraph_bench [keyframes...=250 500 1000 2500]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "posegraph/pose_graph.h"

namespace {

using objmap::PoseGraph;
using objmap::PoseGraphEdge;

Eigen::Matrix<double, 6, 6> Information(double sigma_m, double sigma_rad) {
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes;
  for (int i = 1; i < argc; ++i) sizes.push_back(std::atoi(argv[i]));
  if (sizes.empty()) sizes = {250, 500, 1000, 2500};
  std::printf(
      "| keyframes | loops | dropped as wrong | solve ms | iterations | RMSE before m | RMSE "
      "after m |\n|---|---|---|---|---|---|---|\n");
  for (int n : sizes) {
    std::mt19937 random(7);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::uniform_real_distribution<double> turn(-0.3, 0.3);
    std::vector<Eigen::Isometry3d> truth;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int i = 0; i < n; ++i) {
      truth.push_back(T);
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      // Turn back towards the room's centre when leaving it.
      const double away = T.translation().head<2>().norm() > 2.0 ? 0.5 : 0.0;
      step.rotate(Eigen::AngleAxisd(turn(random) + away, Eigen::Vector3d::UnitZ()));
      step.translation() = Eigen::Vector3d(0.1, 0.0, 0.01 * noise(random));
      T = T * step;
    }
    PoseGraph graph;
    graph.AddNode(0, truth[0]);
    Eigen::Isometry3d chained = truth[0];
    std::string why;
    for (int i = 1; i < n; ++i) {
      Eigen::Isometry3d step = truth[i - 1].inverse() * truth[i];
      step.translation() += 0.003 * Eigen::Vector3d(noise(random), noise(random), noise(random));
      step.rotate(Eigen::AngleAxisd(0.001 + 0.002 * noise(random), Eigen::Vector3d::UnitZ()));
      chained = chained * step;
      graph.AddNode(i, chained);
      PoseGraphEdge edge;
      edge.from = i - 1;
      edge.to = i;
      edge.T_from_to = step;
      edge.information = Information(0.005, 0.01);
      if (!graph.AddEdge(edge, &why)) return 1;
    }
    int loops = 0;
    for (int i = 40; i < n; i += 20) {
      for (int j = 0; j + 30 < i; ++j) {
        if ((truth[i].translation() - truth[j].translation()).norm() > 0.3) continue;
        PoseGraphEdge loop;
        loop.from = j;
        loop.to = i;
        loop.T_from_to = truth[j].inverse() * truth[i];
        loop.information = Information(0.01, 0.01);
        loop.loop = true;
        if (!graph.AddEdge(loop, &why)) return 1;
        ++loops;
        break;
      }
    }
    auto rmse = [&] {
      double sum = 0.0;
      for (const auto& [id, pose] : graph.poses()) {
        sum += (pose.translation() - truth[static_cast<std::size_t>(id)].translation()).squaredNorm();
      }
      return std::sqrt(sum / n);
    };
    const double before = rmse();
    objmap::PoseGraphReport report;
    if (!graph.Optimize(&report, &why)) {
      std::fprintf(stderr, "posegraph_bench: %s\n", why.c_str());
      return 1;
    }
    std::printf("| %d | %d | %zu | %.0f | %d | %.3f | %.3f |\n", n, loops,
                report.rejected_loops.size(), report.solve_ms, report.iterations, before, rmse());
  }
  return 0;
}
