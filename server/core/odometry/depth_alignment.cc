#include "odometry/depth_alignment.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace objmap {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool IsSet(const Eigen::Vector3f& v) { return !std::isnan(v.x()); }

// Depth noise (1 sigma) of a structured-light sensor at range z: quantisation grows with z^2
// (Khoshelham and Elberink 2012), plus a floor for the surface itself.
double DepthSigma(double z) { return 0.0015 * z * z + 0.002; }

void ComputeNormals(DepthGrid* grid) {
  DepthGrid& g = *grid;
  g.normals.assign(g.points.size(), Eigen::Vector3f(kNaN, kNaN, kNaN));
  auto at = [&](int x, int y) -> const Eigen::Vector3f& {
    return g.points[static_cast<std::size_t>(y) * g.width + x];
  };
  for (int y = 1; y + 1 < g.height; ++y) {
    for (int x = 1; x + 1 < g.width; ++x) {
      const Eigen::Vector3f& c = at(x, y);
      const Eigen::Vector3f& right = at(x + 1, y);
      const Eigen::Vector3f& left = at(x - 1, y);
      const Eigen::Vector3f& down = at(x, y + 1);
      const Eigen::Vector3f& up = at(x, y - 1);
      if (!IsSet(c) || !IsSet(right) || !IsSet(left) || !IsSet(down) || !IsSet(up)) continue;
      // Neighbours across a depth edge belong to another surface: no normal there.
      const float limit = 0.05f * c.z();
      if ((right - c).norm() > limit || (left - c).norm() > limit || (down - c).norm() > limit ||
          (up - c).norm() > limit) {
        continue;
      }
      Eigen::Vector3f n = (right - left).cross(down - up);
      const float length = n.norm();
      if (!(length > 1e-12f)) continue;
      n /= length;
      if (n.dot(c) > 0.f) n = -n;  // towards the camera
      g.normals[static_cast<std::size_t>(y) * g.width + x] = n;
    }
  }
}

}  // namespace

DepthGrid MakeDepthGrid(const DepthImage& depth, const CameraIntrinsics& intrinsics, int step,
                        double max_depth_m) {
  DepthGrid g;
  if (step < 1 || depth.empty()) return g;
  g.width = depth.width / step;
  g.height = depth.height / step;
  g.fx = intrinsics.fx / step;
  g.fy = intrinsics.fy / step;
  // A cell's centre is pixel (step - 1) / 2 of its block.
  g.cx = (intrinsics.cx - (step - 1) * 0.5) / step;
  g.cy = (intrinsics.cy - (step - 1) * 0.5) / step;
  g.points.assign(static_cast<std::size_t>(g.width) * g.height, Eigen::Vector3f(kNaN, kNaN, kNaN));
  const float far = static_cast<float>(max_depth_m);
  // Depths within 1 cm + 2 % of the nearest are one surface; beyond, a depth edge.
  auto one_surface = [](float nearest, float farthest) {
    return farthest - nearest <= 0.01f + 0.02f * nearest;
  };
  std::vector<float> cell;
  cell.reserve(static_cast<std::size_t>(step) * step);
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      cell.clear();
      float nearest = std::numeric_limits<float>::max(), farthest = 0.f, sum = 0.f;
      for (int dy = 0; dy < step; ++dy) {
        const float* row = depth.depth_m.data() + static_cast<std::size_t>(y * step + dy) * depth.width;
        for (int dx = 0; dx < step; ++dx) {
          const float z = row[x * step + dx];
          if (!(z > 0.f) || z > far) continue;  // also NaN
          nearest = std::min(nearest, z);
          farthest = std::max(farthest, z);
          sum += z;
          cell.push_back(z);
        }
      }
      if (2 * cell.size() < static_cast<std::size_t>(step) * step) continue;
      float z = sum / static_cast<float>(cell.size());
      if (!one_surface(nearest, farthest)) {
        // Then the middle 80 % of the depths decide: the extremes of a cell's 16-64 samples are
        // the sensor's noise (a structured-light sensor's sigma at 3 m is about 1.5 cm, the
        // range of 64 such samples about 5 sigma: the whole range dropped most cells beyond
        // 2.5 m) or a few pixels of another surface at the cell's rim.
        const std::size_t trim = cell.size() / 10;
        const auto low = cell.begin() + static_cast<std::ptrdiff_t>(trim);
        const auto high = cell.end() - 1 - static_cast<std::ptrdiff_t>(trim);
        std::nth_element(cell.begin(), low, cell.end());
        std::nth_element(low + 1, high, cell.end());
        if (!one_surface(*low, *high)) continue;
        // Between low and high lie the middle depths (nth_element's partitions).
        z = std::accumulate(low, high + 1, 0.f) / static_cast<float>(high - low + 1);
      }
      g.points[static_cast<std::size_t>(y) * g.width + x] =
          Eigen::Vector3f(static_cast<float>((x - g.cx) * z / g.fx),
                          static_cast<float>((y - g.cy) * z / g.fy), z);
    }
  }
  ComputeNormals(&g);
  return g;
}

bool AlignDepth(const std::vector<const DepthGrid*>& model_levels,
                const std::vector<const DepthGrid*>& frame_levels,
                const std::vector<DepthAlignmentLevel>& levels, int min_correspondences,
                Eigen::Isometry3d* T_model_frame, DepthAlignmentReport* report) {
  *report = DepthAlignmentReport();
  if (model_levels.size() != levels.size() || frame_levels.size() != levels.size()) return false;
  Eigen::Isometry3d T = *T_model_frame;
  for (std::size_t level = 0; level < levels.size(); ++level) {
    const DepthGrid& model = *model_levels[level];
    const DepthGrid& frame = *frame_levels[level];
    const DepthAlignmentLevel& schedule = levels[level];
    if (model.empty() || frame.empty()) return false;
    for (int iteration = 0; iteration < schedule.iterations; ++iteration) {
      const double fraction =
          schedule.iterations > 1 ? iteration / static_cast<double>(schedule.iterations - 1) : 1.0;
      const float max_distance = static_cast<float>(
          schedule.first_max_distance_m +
          (schedule.last_max_distance_m - schedule.first_max_distance_m) * fraction);
      Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
      double squared_sum = 0.0;
      int used = 0;
      Eigen::Vector3d point_sum = Eigen::Vector3d::Zero();
      double point_squared_sum = 0.0;
      const Eigen::Matrix3f R = T.linear().cast<float>();
      const Eigen::Vector3f t = T.translation().cast<float>();
      for (std::size_t i = 0; i < frame.points.size(); ++i) {
        const Eigen::Vector3f& p = frame.points[i];
        if (!IsSet(p) || !IsSet(frame.normals[i])) continue;
        const Eigen::Vector3f q = R * p + t;
        if (!(q.z() > 0.f)) continue;
        const long x = std::lround(model.fx * q.x() / q.z() + model.cx);
        const long y = std::lround(model.fy * q.y() / q.z() + model.cy);
        if (x < 0 || y < 0 || x >= model.width || y >= model.height) continue;
        const std::size_t j = static_cast<std::size_t>(y) * model.width + static_cast<std::size_t>(x);
        const Eigen::Vector3f& v = model.points[j];
        const Eigen::Vector3f& n = model.normals[j];
        if (!IsSet(v) || !IsSet(n) || (q - v).norm() > max_distance) continue;
        // Surfaces facing differently are different surfaces (about 37 degrees).
        if (n.dot(R * frame.normals[i]) < 0.8f) continue;
        const double residual = n.dot(q - v);
        // Left perturbation T <- exp(xi) T: dq = v + w x q, so d(n.q) = n.v + w.(q x n).
        Eigen::Matrix<double, 6, 1> J;
        J.head<3>() = n.cast<double>();
        J.tail<3>() = q.cast<double>().cross(n.cast<double>());
        const double sigma = DepthSigma(q.z());
        double weight = 1.0 / (sigma * sigma);
        const double huber = 2.0 * sigma;
        if (std::abs(residual) > huber) weight *= huber / std::abs(residual);
        H.noalias() += weight * J * J.transpose();
        g.noalias() -= weight * J * residual;
        squared_sum += residual * residual;
        point_sum += q.cast<double>();
        point_squared_sum += q.cast<double>().squaredNorm();
        ++used;
      }
      report->correspondences = used;
      if (used < min_correspondences) return false;
      report->rmse_m = std::sqrt(squared_sum / used);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(H, Eigen::EigenvaluesOnly);
      report->conditioning = eigen.eigenvalues()(5) > 0.0 ? eigen.eigenvalues()(0) / eigen.eigenvalues()(5) : 0.0;
      // About the centroid c instead of the origin: dt_origin = dt_c + c x dtheta.
      const Eigen::Vector3d c = point_sum / used;
      Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Identity();
      M.block<3, 3>(0, 3) << 0.0, -c.z(), c.y(), c.z(), 0.0, -c.x(), -c.y(), c.x(), 0.0;
      report->hessian = M.transpose() * H * M;
      report->centre = c;
      report->radius_m = std::sqrt(std::max(0.0, point_squared_sum / used - c.squaredNorm()));
      const Eigen::Matrix<double, 6, 1> xi = H.ldlt().solve(g);
      if (!xi.allFinite()) return false;
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      const Eigen::Vector3d w = xi.tail<3>();
      if (w.norm() > 0.0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
      step.translation() = xi.head<3>();
      T = step * T;
      ++report->iterations;
      if (xi.head<3>().norm() < 1e-5 && w.norm() < 1e-5) break;  // 10 um, 0.6 mdeg: converged
    }
  }
  *T_model_frame = T;
  return true;
}

}  // namespace objmap
