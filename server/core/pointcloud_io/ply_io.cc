// Binary PLY of coloured points, written and read back by hand: the format is small, and this
// keeps PCL out of the path.
#include <cstring>
#include <fstream>
#include <sstream>

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

bool ReadPly(const std::string& path, std::vector<Eigen::Vector3f>* points,
             std::vector<std::array<std::uint8_t, 3>>* colors, std::string* why) {
  points->clear();
  colors->clear();
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = path + ": cannot be opened";
    return false;
  }
  // The header WritePly writes; anything else is refused rather than misread.
  std::string line, header;
  std::size_t count = 0;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string word, element;
    words >> word;
    if (word == "element" && (words >> element >> count) && element == "vertex") continue;
    header += line + "\n";
  }
  const char kExpected[] =
      "ply\nformat binary_little_endian 1.0\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (line != "end_header" || header != kExpected || !IsLittleEndian()) {
    *why = path + ": not a binary little-endian PLY of x y z float, red green blue uchar vertices";
    return false;
  }
  std::vector<char> buffer(count * 15);
  in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  if (static_cast<std::size_t>(in.gcount()) != buffer.size()) {
    *why = path + ": " + std::to_string(count) + " vertices announced, the file ends before";
    return false;
  }
  points->resize(count);
  colors->resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    std::memcpy((*points)[i].data(), buffer.data() + i * 15, 12);
    std::memcpy((*colors)[i].data(), buffer.data() + i * 15 + 12, 3);
  }
  return true;
}

}  // namespace objmap
