// Bytes read back from the store's database, as a damaged file would give them: every decoder
// of the keyframe codec. The first byte picks the decoder, the next two the expected size.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "store/keyframe_codec.h"

namespace codec = objmap::store_internal;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  const int which = data[0] % 9;
  const int width = 1 + data[1] % 64, height = 1 + data[2] % 64;
  data += 3;
  size -= 3;
  std::string why;
  switch (which) {
    case 0: {
      std::vector<std::uint16_t> depth;
      if (codec::DecodeDepthPng(data, size, width, height, &depth, &why) &&
          depth.size() != static_cast<std::size_t>(width) * height) {
        __builtin_trap();
      }
      break;
    }
    case 1: {
      std::vector<std::uint8_t> mask;
      if (codec::DecodeMaskPng(data, size, width, height, &mask, &why) &&
          mask.size() != static_cast<std::size_t>(width) * height) {
        __builtin_trap();
      }
      break;
    }
    case 2: {
      objmap::ColorImage color;
      (void)codec::DecodeColorJpeg(data, size, width, height, &color, &why);
      break;
    }
    case 3: {
      Eigen::Isometry3d T;
      (void)codec::UnpackPose(data, size, &T);
      break;
    }
    case 4: {
      std::vector<objmap::Detection> detections;
      (void)codec::UnpackDetections(data, size, &detections);
      break;
    }
    case 5: {
      std::vector<std::pair<int, float>> scores;
      (void)codec::UnpackClassScores(data, size, &scores);
      break;
    }
    case 6: {
      // xyz and rgb blobs side by side, split where the pick says.
      const std::size_t split = size == 0 ? 0 : (static_cast<std::size_t>(width) * 97) % (size + 1);
      objmap::ColoredPoints points;
      if (codec::UnpackColoredPoints(data, split, data + split, size - split, &points) &&
          !points.colors.empty() && points.colors.size() != points.points.size()) {
        __builtin_trap();
      }
      break;
    }
    case 7: {
      // An observation's pixels: whatever is accepted is ascending, disjoint runs.
      objmap::PixelRuns runs;
      float voxel = 0.f;
      std::size_t points = 0;
      if (codec::UnpackSegmentPixels(data, size, &runs, &voxel, &points)) {
        std::uint64_t end = 0;
        for (const objmap::PixelRun& run : runs) {
          if (run.length == 0 || run.start < end) __builtin_trap();
          end = std::uint64_t{run.start} + run.length;
        }
        if (!(voxel > 0.f)) __builtin_trap();
      }
      break;
    }
    case 8: {
      // An observation's colours: as many as asked for, or refused.
      std::vector<std::array<std::uint8_t, 3>> colors;
      const std::size_t count = static_cast<std::size_t>(width) * height;
      if (codec::DecodeSegmentColorsPng(data, size, count, &colors, &why) &&
          colors.size() != (size == 0 ? 0 : count)) {
        __builtin_trap();
      }
      break;
    }
    default:
      break;
  }
  return 0;
}
