#include "objects/observation_segment.h"

#include <algorithm>
#include <cmath>

#include "types/rounding.h"

namespace objmap {

PixelRuns RunsOf(std::vector<int> pixels) {
  std::sort(pixels.begin(), pixels.end());
  PixelRuns runs;
  for (int pixel : pixels) {
    if (pixel < 0) continue;
    const auto index = static_cast<std::uint32_t>(pixel);
    if (!runs.empty() && index < runs.back().start + runs.back().length) continue;  // a repeat
    if (!runs.empty() && index == runs.back().start + runs.back().length) {
      ++runs.back().length;
    } else {
      runs.push_back({index, 1});
    }
  }
  return runs;
}

std::size_t PixelCount(const PixelRuns& runs) {
  std::size_t count = 0;
  for (const PixelRun& run : runs) count += run.length;
  return count;
}

std::uint16_t DepthSampleMillimetres(float depth_m) {
  const bool valid = std::isfinite(depth_m) && depth_m > 0.f && depth_m < 65.f;
  return valid ? static_cast<std::uint16_t>(RoundNonNegative(depth_m * 1000.f)) : 0;
}

ColoredPoints SegmentPointsFromDepth(const std::vector<std::uint16_t>& depth_mm,
                                     const CameraIntrinsics& intrinsics, const PixelRuns& runs,
                                     float voxel_size_m,
                                     const std::vector<std::array<std::uint8_t, 3>>* rgb) {
  const std::size_t width = static_cast<std::size_t>(std::max(intrinsics.width, 1));
  const std::size_t pixels =
      std::min(depth_mm.size(), width * static_cast<std::size_t>(std::max(intrinsics.height, 0)));
  const bool with_color = rgb != nullptr && rgb->size() >= pixels;
  const float inv_fx = 1.f / static_cast<float>(intrinsics.fx);
  const float inv_fy = 1.f / static_cast<float>(intrinsics.fy);
  const float cx = static_cast<float>(intrinsics.cx);
  const float cy = static_cast<float>(intrinsics.cy);
  ColoredPoints points;
  points.points.reserve(PixelCount(runs));
  for (const PixelRun& run : runs) {
    const std::size_t end = std::min<std::size_t>(pixels, std::size_t{run.start} + run.length);
    for (std::size_t i = run.start; i < end; ++i) {
      if (depth_mm[i] == 0) continue;
      const float z = DepthSampleMetres(depth_mm[i]);
      const float u = static_cast<float>(i % width);
      const float v = static_cast<float>(i / width);
      points.points.emplace_back((u - cx) * z * inv_fx, (v - cy) * z * inv_fy, z);
      if (with_color) points.colors.push_back((*rgb)[i]);
    }
  }
  return VoxelDownsample(points, voxel_size_m);
}

}  // namespace objmap
