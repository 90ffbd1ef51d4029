// Binary PLY writer: small enough to write by hand, and it keeps PCL out of this path.
#include <cstring>
#include <fstream>

#include "pointcloud_io/pointcloud_io.h"

namespace objmap {
namespace {

bool IsLittleEndian() {
  const std::uint16_t probe = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

}  // namespace

bool WritePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
              const std::vector<std::array<std::uint8_t, 3>>& colors, std::string* why) {
  if (!colors.empty() && colors.size() != points.size()) {
    if (why) *why = "WritePly: colors must be empty or one per point";
    return false;
  }
  if (!IsLittleEndian()) {
    if (why) *why = "WritePly: big-endian hosts are not supported";
    return false;
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) {
    if (why) *why = "cannot open " + path + " for writing";
    return false;
  }
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  std::vector<char> buffer(points.size() * 15);
  for (size_t i = 0; i < points.size(); ++i) {
    char* dst = buffer.data() + i * 15;
    std::memcpy(dst, points[i].data(), 12);
    const std::array<std::uint8_t, 3> rgb =
        colors.empty() ? std::array<std::uint8_t, 3>{255, 255, 255} : colors[i];
    std::memcpy(dst + 12, rgb.data(), 3);
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (!out) {
    if (why) *why = "write failed for " + path;
    return false;
  }
  return true;
}

}  // namespace objmap
