#include "map_server/revisit_thinning.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace objmap {

bool RevisitThinningConfig::IsValid(std::string* why) const {
  if (!(max_distance_m >= 0.0) || !(max_angle_deg >= 0.0 && max_angle_deg <= 180.0)) {
    *why = "thinning: max_distance_m must be >= 0 and max_angle_deg in [0, 180]";
    return false;
  }
  if (max_views < 1 || pixel_stride < 1 || pixel_stride > 64) {
    *why = "thinning: max_views must be >= 1 and pixel_stride in [1, 64]";
    return false;
  }
  if (!(depth_margin_m >= 0.f) || !(depth_margin_per_m2 >= 0.f) ||
      !(max_contradicted_patch_px >= 0.f)) {
    *why =
        "thinning: depth_margin_m, depth_margin_per_m2 and max_contradicted_patch_px must be >= 0";
    return false;
  }
  if (!(min_explained_fraction > 0.f && min_explained_fraction <= 1.f) ||
      !(min_depth_fraction >= 0.f && min_depth_fraction <= 1.f)) {
    *why = "thinning: min_explained_fraction must be in (0, 1] and min_depth_fraction in [0, 1]";
    return false;
  }
  return true;
}

bool IsNearbyView(const Eigen::Isometry3d& stored_W_C, const Eigen::Isometry3d& T_W_C,
                  const RevisitThinningConfig& config) {
  if ((stored_W_C.translation() - T_W_C.translation()).norm() > config.max_distance_m) {
    return false;
  }
  const Eigen::Vector3d axis_a = stored_W_C.linear().col(2);
  const Eigen::Vector3d axis_b = T_W_C.linear().col(2);
  const double cos_angle = std::clamp(axis_a.dot(axis_b), -1.0, 1.0);
  return std::acos(cos_angle) * 180.0 / M_PI <= config.max_angle_deg;
}

namespace {

// What a stored view says of a point the new keyframe measured.
enum class Verdict {
  kUnseen,       // outside its image, or no depth there: it says nothing
  kExplained,    // it measured the point (within the margin along its ray)
  kContradicted  // it measured something else there: nearer or farther
};

// `view`'s verdict on p_W, at the pixel p_W projects to or one of its 8 neighbours (depth edges
// move by a pixel between views).
Verdict Judge(const StoredView& view, const Eigen::Isometry3d& T_C_W, const Eigen::Vector3d& p_W,
              const RevisitThinningConfig& config) {
  const Eigen::Vector3d p_C = T_C_W * p_W;
  if (p_C.z() <= 0.05) return Verdict::kUnseen;
  const CameraIntrinsics& intrinsics = *view.intrinsics;
  const double u = intrinsics.fx * p_C.x() / p_C.z() + intrinsics.cx;
  const double v = intrinsics.fy * p_C.y() / p_C.z() + intrinsics.cy;
  const int col = static_cast<int>(std::lround(u));
  const int row = static_cast<int>(std::lround(v));
  if (col < 0 || row < 0 || col >= intrinsics.width || row >= intrinsics.height) {
    return Verdict::kUnseen;
  }
  const float z = static_cast<float>(p_C.z());
  const float margin_mm = 1000.f * (config.depth_margin_m + config.depth_margin_per_m2 * z * z);
  const float z_mm = 1000.f * z;
  const std::vector<std::uint16_t>& depth = *view.depth_mm;
  bool measured_any = false;
  for (int dr = -1; dr <= 1; ++dr) {
    const int r = row + dr;
    if (r < 0 || r >= intrinsics.height) continue;
    for (int dc = -1; dc <= 1; ++dc) {
      const int c = col + dc;
      if (c < 0 || c >= intrinsics.width) continue;
      const std::uint16_t measured = depth[static_cast<std::size_t>(r) * intrinsics.width + c];
      if (measured == 0) continue;
      measured_any = true;
      if (std::abs(static_cast<float>(measured) - z_mm) <= margin_mm) return Verdict::kExplained;
    }
  }
  return measured_any ? Verdict::kContradicted : Verdict::kUnseen;
}

// The size (in samples) of the largest 8-connected set of true cells of a grid.
int LargestPatch(std::vector<std::uint8_t> cells, int cols, int rows) {
  int largest = 0;
  std::vector<int> stack;
  for (int start = 0; start < cols * rows; ++start) {
    if (cells[start] == 0) continue;
    cells[start] = 0;
    stack.assign(1, start);
    int size = 0;
    while (!stack.empty()) {
      const int cell = stack.back();
      stack.pop_back();
      ++size;
      const int r = cell / cols, c = cell % cols;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int nr = r + dr, nc = c + dc;
          if (nr < 0 || nc < 0 || nr >= rows || nc >= cols) continue;
          const int next = nr * cols + nc;
          if (cells[next] == 0) continue;
          cells[next] = 0;
          stack.push_back(next);
        }
      }
    }
    largest = std::max(largest, size);
  }
  return largest;
}

}  // namespace

ViewCoverage CoverageOf(const DepthImage& depth, const CameraIntrinsics& intrinsics,
                        const Eigen::Isometry3d& T_W_C, const std::vector<StoredView>& views,
                        const RevisitThinningConfig& config) {
  ViewCoverage coverage;
  const int stride = config.pixel_stride;
  const int cols = (depth.width + stride - 1) / stride;
  const int rows = (depth.height + stride - 1) / stride;
  if (cols <= 0 || rows <= 0) return coverage;
  std::vector<Eigen::Isometry3d> T_C_W;
  for (const StoredView& view : views) T_C_W.push_back(view.T_W_C.inverse());
  // Samples some view contradicts and none explains: what changed (or was hidden from them).
  std::vector<std::uint8_t> contradicted(static_cast<std::size_t>(cols) * rows, 0);
  std::map<std::int64_t, int> explained_by;
  int explained = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int row = r * stride, col = c * stride;
      const float z = depth.depth_m[static_cast<std::size_t>(row) * depth.width + col];
      if (!std::isfinite(z) || z <= 0.f) continue;
      ++coverage.depth_pixels;
      const Eigen::Vector3d p_C((col - intrinsics.cx) * z / intrinsics.fx,
                                (row - intrinsics.cy) * z / intrinsics.fy, z);
      const Eigen::Vector3d p_W = T_W_C * p_C;
      bool found = false, against = false;
      for (std::size_t i = 0; i < views.size() && !found; ++i) {
        const Verdict verdict = Judge(views[i], T_C_W[i], p_W, config);
        if (verdict == Verdict::kExplained) {
          found = true;
          ++explained_by[views[i].keyframe_id];
        }
        against |= verdict == Verdict::kContradicted;
      }
      if (found) {
        ++explained;
      } else if (against) {
        contradicted[static_cast<std::size_t>(r) * cols + c] = 1;
      }
    }
  }
  if (coverage.depth_pixels == 0) return coverage;
  coverage.explained_fraction = static_cast<float>(explained) / coverage.depth_pixels;
  coverage.largest_contradicted_patch_px =
      static_cast<float>(LargestPatch(std::move(contradicted), cols, rows)) * stride * stride;
  int best = 0;
  for (const auto& [id, count] : explained_by) {
    if (count > best) {
      best = count;
      coverage.best_keyframe = id;
    }
  }
  const float depth_fraction =
      static_cast<float>(coverage.depth_pixels) / (static_cast<float>(cols) * rows);
  coverage.repeated = depth_fraction >= config.min_depth_fraction &&
                      coverage.explained_fraction >= config.min_explained_fraction &&
                      coverage.largest_contradicted_patch_px <= config.max_contradicted_patch_px;
  return coverage;
}

}  // namespace objmap
