#pragma once
// An observation's points are what its keyframe's depth shows at the segment's pixels, voxel-
// downsampled. The keyframe's depth is stored anyway (in millimetres, for regeneration), so the
// store keeps the segment's pixels instead of its points: a few hundred runs instead of 15 bytes
// a point. The mapper makes the points with the same function the store rebuilds them with, from
// the same millimetres, so a restart finds the points it had, bit for bit.

#include <cstdint>
#include <vector>

#include "objects/voxel_model.h"
#include "types/frame.h"

namespace objmap {

/// Pixels [start, start + length) of a row-major image.
struct PixelRun {
  std::uint32_t start = 0;
  std::uint32_t length = 0;

  bool operator==(const PixelRun& other) const {
    return start == other.start && length == other.length;
  }
};

/// A set of pixels as ascending, disjoint, non-adjacent runs.
using PixelRuns = std::vector<PixelRun>;

/// The runs of `pixels` (row-major indices, any order, repeats allowed; negative ones ignored).
[[nodiscard]] PixelRuns RunsOf(std::vector<int> pixels);
[[nodiscard]] std::size_t PixelCount(const PixelRuns& runs);

/// A depth sample in millimetres as a keyframe keeps it: rounded, 0 where there is none (not
/// finite, not positive, or 65 m and beyond).
[[nodiscard]] std::uint16_t DepthSampleMillimetres(float depth_m);
/// The metres a kept sample stands for (0: none). Every reader of kept depth converts with it.
[[nodiscard]] inline float DepthSampleMetres(std::uint16_t depth_mm) { return depth_mm * 0.001f; }

/// The segment `runs` of a keyframe: its pixels with depth in `depth_mm` (row-major,
/// intrinsics.width x intrinsics.height, DepthSampleMillimetres) back-projected through
/// `intrinsics` and voxel-downsampled at `voxel_size_m` (VoxelDownsample, pixels in ascending
/// order). Colours are averaged from `rgb` (one per pixel) when it is not null, and left empty
/// otherwise. Runs beyond the image are ignored.
[[nodiscard]] ColoredPoints SegmentPointsFromDepth(
    const std::vector<std::uint16_t>& depth_mm, const CameraIntrinsics& intrinsics,
    const PixelRuns& runs, float voxel_size_m, const std::vector<std::array<std::uint8_t, 3>>* rgb);

}  // namespace objmap
