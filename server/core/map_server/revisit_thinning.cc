#include "map_server/revisit_thinning.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "mapper/mapper.h"
#include "objects/observation_segment.h"

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
  if (!(depth_margin_m >= 0.f) || !(depth_margin_per_m2 >= 0.f) || !(max_changed_patch_px >= 0.f)) {
    *why = "thinning: depth_margin_m, depth_margin_per_m2 and max_changed_patch_px must be >= 0";
    return false;
  }
  if (!(min_explained_fraction > 0.f && min_explained_fraction <= 1.f) ||
      !(min_depth_fraction >= 0.f && min_depth_fraction <= 1.f)) {
    *why = "thinning: min_explained_fraction must be in (0, 1] and min_depth_fraction in [0, 1]";
    return false;
  }
  if (!(min_partial_explained_fraction > 0.f && min_partial_explained_fraction <= 1.f) ||
      !(min_new_fraction_in_box >= 0.f && min_new_fraction_in_box <= 1.f) ||
      !(box_margin >= 0.f && box_margin <= 10.f)) {
    *why =
        "thinning: min_partial_explained_fraction must be in (0, 1], min_new_fraction_in_box in "
        "[0, 1] and box_margin in [0, 10]";
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

// What a depth image says of a point at depth z (metres) along the ray of one of its pixels.
enum class Verdict {
  kUnseen,     // outside the image, no depth there, or something nearer hides it
  kExplained,  // it measured the point (within the margin along its ray)
  kInFront     // it measured something farther: its ray went through where the point is
};

float MarginMm(float z, const RevisitThinningConfig& config) {
  return 1000.f * (config.depth_margin_m + config.depth_margin_per_m2 * z * z);
}

// The verdict of a camera's depth image (millimetres, row-major, `k`-sized) on the point p_C
// of its own frame, at the pixel it projects to and that pixel's 8 neighbours (depth edges move
// by a pixel between views): in front only when every neighbour with depth measured beyond it.
// The pixel goes to `col`, `row` (may be null) when the point projects into the image.
Verdict Judge(const std::vector<std::uint16_t>& depth_mm, const CameraIntrinsics& k,
              const Eigen::Vector3d& p_C, const RevisitThinningConfig& config,
              int* col_out = nullptr, int* row_out = nullptr) {
  if (p_C.z() <= 0.05) return Verdict::kUnseen;
  const int col = static_cast<int>(std::lround(k.fx * p_C.x() / p_C.z() + k.cx));
  const int row = static_cast<int>(std::lround(k.fy * p_C.y() / p_C.z() + k.cy));
  if (col < 0 || row < 0 || col >= k.width || row >= k.height) return Verdict::kUnseen;
  if (col_out != nullptr) *col_out = col;
  if (row_out != nullptr) *row_out = row;
  const float z = static_cast<float>(p_C.z());
  const float margin_mm = MarginMm(z, config);
  const float z_mm = 1000.f * z;
  bool measured_any = false, all_beyond = true;
  for (int dr = -1; dr <= 1; ++dr) {
    const int r = row + dr;
    if (r < 0 || r >= k.height) continue;
    for (int dc = -1; dc <= 1; ++dc) {
      const int c = col + dc;
      if (c < 0 || c >= k.width) continue;
      const std::uint16_t measured = depth_mm[static_cast<std::size_t>(r) * k.width + c];
      if (measured == 0) continue;
      measured_any = true;
      const float difference = static_cast<float>(measured) - z_mm;
      if (std::abs(difference) <= margin_mm) return Verdict::kExplained;
      all_beyond &= difference > margin_mm;
    }
  }
  return measured_any && all_beyond ? Verdict::kInFront : Verdict::kUnseen;
}

// A box's pixels (inclusive), within an image of this size.
struct PixelRect {
  int col_min = 0, row_min = 0, col_max = -1, row_max = -1;
};

PixelRect Clamped(const BoundingBox2D& box, int width, int height) {
  return {std::max(0, static_cast<int>(std::floor(box.x_min))),
          std::max(0, static_cast<int>(std::floor(box.y_min))),
          std::min(width - 1, static_cast<int>(std::ceil(box.x_max))),
          std::min(height - 1, static_cast<int>(std::ceil(box.y_max)))};
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
  // Samples that show a change: something put down (a stored view's ray went through the
  // point the new keyframe measured, and no view measured it), or something taken away (the new
  // keyframe's ray goes through a point a stored view measured). A point a stored view could not
  // see, behind what it measured, is only new to it.
  std::vector<std::uint8_t> changed(static_cast<std::size_t>(cols) * rows, 0);
  std::map<std::int64_t, int> explained_by;
  int explained = 0;
  coverage.explained.assign(static_cast<std::size_t>(cols) * rows, 0);
  coverage.grid_cols = cols;
  coverage.grid_rows = rows;
  coverage.stride = stride;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int row = r * stride, col = c * stride;
      const float z = depth.depth_m[static_cast<std::size_t>(row) * depth.width + col];
      if (!std::isfinite(z) || z <= 0.f) continue;
      ++coverage.depth_pixels;
      const Eigen::Vector3d p_C((col - intrinsics.cx) * z / intrinsics.fx,
                                (row - intrinsics.cy) * z / intrinsics.fy, z);
      const Eigen::Vector3d p_W = T_W_C * p_C;
      bool found = false, put_down = false;
      for (std::size_t i = 0; i < views.size() && !found; ++i) {
        const Verdict verdict =
            Judge(*views[i].depth_mm, *views[i].intrinsics, T_C_W[i] * p_W, config);
        if (verdict == Verdict::kExplained) {
          found = true;
          ++explained_by[views[i].keyframe_id];
        }
        put_down |= verdict == Verdict::kInFront;
      }
      if (found) {
        ++explained;
        coverage.explained[static_cast<std::size_t>(r) * cols + c] = 1;
      } else if (put_down) {
        changed[static_cast<std::size_t>(r) * cols + c] = 1;
      }
    }
  }
  // Taken away: the stored views' points, judged by the new keyframe's depth in millimetres.
  const std::vector<std::uint16_t> depth_mm = DepthMillimetres(depth);
  const Eigen::Isometry3d T_C_W_new = T_W_C.inverse();
  for (const StoredView& view : views) {
    const CameraIntrinsics& k = *view.intrinsics;
    const Eigen::Isometry3d T_new_view = T_C_W_new * view.T_W_C;
    for (int row = 0; row < k.height; row += stride) {
      for (int col = 0; col < k.width; col += stride) {
        const std::uint16_t measured =
            (*view.depth_mm)[static_cast<std::size_t>(row) * k.width + col];
        if (measured == 0) continue;
        const float z_view = DepthSampleMetres(measured);
        const Eigen::Vector3d q_view((col - k.cx) * z_view / k.fx, (row - k.cy) * z_view / k.fy,
                                     z_view);
        int new_col = 0, new_row = 0;
        if (Judge(depth_mm, intrinsics, T_new_view * q_view, config, &new_col, &new_row) ==
            Verdict::kInFront) {
          changed[static_cast<std::size_t>(new_row / stride) * cols + new_col / stride] = 1;
        }
      }
    }
  }
  if (coverage.depth_pixels == 0) return coverage;
  coverage.explained_fraction = static_cast<float>(explained) / coverage.depth_pixels;
  coverage.largest_changed_patch_px =
      static_cast<float>(LargestPatch(std::move(changed), cols, rows)) * stride * stride;
  int best = 0;
  for (const auto& [id, count] : explained_by) {
    if (count > best) {
      best = count;
      coverage.best_keyframe = id;
    }
  }
  const float depth_fraction =
      static_cast<float>(coverage.depth_pixels) / (static_cast<float>(cols) * rows);
  const bool unchanged = depth_fraction >= config.min_depth_fraction &&
                         coverage.largest_changed_patch_px <= config.max_changed_patch_px;
  coverage.repeated = unchanged && coverage.explained_fraction >= config.min_explained_fraction;
  coverage.repeated_in_part = unchanged && !coverage.repeated &&
                              coverage.explained_fraction >= config.min_partial_explained_fraction;
  return coverage;
}

void KeepUnexplained(const ViewCoverage& coverage, const std::vector<BoundingBox2D>& boxes,
                     const RevisitThinningConfig& config, DepthImage* depth) {
  if (coverage.grid_cols <= 0 || coverage.stride <= 0) return;
  const int stride = coverage.stride;
  auto sample = [&](int row, int col) {
    const int r = std::min(row / stride, coverage.grid_rows - 1);
    const int c = std::min(col / stride, coverage.grid_cols - 1);
    return static_cast<std::size_t>(r) * coverage.grid_cols + c;
  };
  auto has_depth = [&](int row, int col) {
    const float z = depth->depth_m[static_cast<std::size_t>(row) * depth->width + col];
    return std::isfinite(z) && z > 0.f;
  };
  // The boxes kept whole (1) or left out whole (2), judged on the compared pixels (those that
  // start a block): a part of a box would be segmented as a fragment of its object.
  std::vector<std::uint8_t> keep(depth->depth_m.size(), 0);
  std::vector<PixelRect> left_out;
  for (const BoundingBox2D& box : boxes) {
    const PixelRect rect = Clamped(box, depth->width, depth->height);
    const auto [col_min, row_min, col_max, row_max] = rect;
    int compared = 0, fresh = 0;
    for (int row = row_min; row <= row_max; ++row) {
      if (row % stride != 0) continue;
      for (int col = col_min; col <= col_max; ++col) {
        if (col % stride != 0 || !has_depth(row, col)) continue;
        ++compared;
        fresh += coverage.explained[sample(row, col)] == 0;
      }
    }
    if (compared == 0) continue;
    if (fresh < config.min_new_fraction_in_box * compared) {
      left_out.push_back(rect);
      continue;
    }
    // With the surface around it: the segmentation tells the object from its support by the
    // plane it stands on.
    const int margin_cols = static_cast<int>(config.box_margin * (col_max - col_min));
    const int margin_rows = static_cast<int>(config.box_margin * (row_max - row_min));
    const int keep_col_min = std::max(0, col_min - margin_cols);
    const int keep_col_max = std::min(depth->width - 1, col_max + margin_cols);
    for (int row = std::max(0, row_min - margin_rows);
         row <= std::min(depth->height - 1, row_max + margin_rows); ++row) {
      std::fill(keep.begin() + static_cast<std::ptrdiff_t>(row) * depth->width + keep_col_min,
                keep.begin() + static_cast<std::ptrdiff_t>(row) * depth->width + keep_col_max + 1,
                1);
    }
  }
  for (const PixelRect& rect : left_out) {
    for (int row = rect.row_min; row <= rect.row_max; ++row) {
      for (int col = rect.col_min; col <= rect.col_max; ++col) {
        std::uint8_t& mark = keep[static_cast<std::size_t>(row) * depth->width + col];
        if (mark == 0) mark = 2;
      }
    }
  }
  for (int row = 0; row < depth->height; ++row) {
    for (int col = 0; col < depth->width; ++col) {
      const std::size_t i = static_cast<std::size_t>(row) * depth->width + col;
      if (keep[i] == 2 || (keep[i] == 0 && coverage.explained[sample(row, col)] != 0)) {
        depth->depth_m[i] = 0.f;
      }
    }
  }
}

}  // namespace objmap
