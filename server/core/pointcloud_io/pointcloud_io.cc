#include "pointcloud_io/pointcloud_io.h"

#include <pcl/io/lzf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

namespace objmap {
namespace {

// PCD files are read here rather than by PCL's PCDReader, which trusts the header: an empty
// file, an unknown header line or a body shorter than the header promises crash it (found by
// tests/fuzz/pcd_reader_fuzzer.cc). Every size is checked before it is used.
struct PcdField {
  std::string name;
  std::uint64_t size = 0;   // bytes per element
  char type = '?';          // F, I or U
  std::uint64_t count = 1;  // elements
  std::uint64_t offset = 0;  // in the packed point
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::uint64_t width = 0, height = 0, point_bytes = 0;
  std::string data;  // ascii, binary or binary_compressed
};

bool ParsePcdHeader(std::istream& file, const std::string& path, PcdHeader* header,
                    std::string* why) {
  constexpr std::uint64_t kMaxPoints = std::uint64_t{1} << 26;
  const auto fail = [&](const std::string& problem) {
    *why = path + ": not a valid PCD file: " + problem;
    return false;
  };
  std::vector<std::string> names;
  std::vector<std::uint64_t> sizes, counts;
  std::vector<char> types;
  std::uint64_t points = 0;
  bool has_points = false;
  std::set<std::string> seen_keys;
  std::string line;
  for (int lines = 0; header->data.empty(); ++lines) {
    if (lines > 64 || !std::getline(file, line)) return fail("no DATA line in its header");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    for (const char c : line) {
      if ((c < ' ' || c > '~') && c != '\t') return fail("a header line holds a control byte");
    }
    std::istringstream words(line);
    std::string key, word;
    words >> key;
    if (!seen_keys.insert(key).second) return fail("header key " + key.substr(0, 32) + " twice");
    if (key == "FIELDS") {
      while (words >> word) names.push_back(word);
    } else if (key == "SIZE" || key == "COUNT") {
      std::vector<std::uint64_t>& list = key == "SIZE" ? sizes : counts;
      while (words >> word) {
        char* end = nullptr;
        list.push_back(std::strtoull(word.c_str(), &end, 10));
        if (*end != '\0') return fail(key + " holds '" + word.substr(0, 16) + "'");
      }
    } else if (key == "TYPE") {
      while (words >> word) types.push_back(word.size() == 1 ? word[0] : '?');
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      std::uint64_t value = 0;
      if (!(words >> value)) return fail(key + " needs a number");
      (key == "WIDTH" ? header->width : key == "HEIGHT" ? header->height : points) = value;
      has_points = has_points || key == "POINTS";
    } else if (key == "DATA") {
      words >> header->data;
      if (header->data != "ascii" && header->data != "binary" &&
          header->data != "binary_compressed") {
        return fail("DATA must be ascii, binary or binary_compressed");
      }
    } else if (key != "VERSION" && key != "VIEWPOINT") {
      return fail("unknown header line '" + key.substr(0, 32) + "'");
    }
  }
  if (names.empty() || sizes.size() != names.size() || types.size() != names.size()) {
    return fail("FIELDS, SIZE and TYPE must list the same number of fields");
  }
  if (counts.empty()) counts.assign(names.size(), 1);
  if (counts.size() != names.size()) return fail("COUNT must list one count per field");
  for (std::size_t i = 0; i < names.size(); ++i) {
    const bool integer_size = sizes[i] == 1 || sizes[i] == 2 || sizes[i] == 4 || sizes[i] == 8;
    const bool float_size = sizes[i] == 4 || sizes[i] == 8;
    if (!(types[i] == 'F' ? float_size : (types[i] == 'I' || types[i] == 'U') && integer_size) ||
        counts[i] < 1 || counts[i] > 1024) {
      return fail("field " + names[i].substr(0, 32) + " has an unknown size, type or count");
    }
    header->fields.push_back({names[i], sizes[i], types[i], counts[i], header->point_bytes});
    header->point_bytes += sizes[i] * counts[i];
  }
  const std::uint64_t width = header->width, height = header->height;
  if (width < 1 || height < 1 || width > kMaxPoints || height > kMaxPoints ||
      width * height > kMaxPoints || !has_points || points != width * height) {
    return fail("WIDTH x HEIGHT must equal POINTS, between 1 and " + std::to_string(kMaxPoints));
  }
  return true;
}

// One ASCII value into `out` (`size` bytes, little-endian as the machine stores it).
bool ParseAsciiValue(const std::string& token, const PcdField& field, std::uint8_t* out) {
  char* end = nullptr;
  if (field.type == 'F') {
    const double value = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') return false;
    if (field.size == 4) {
      const float narrow = static_cast<float>(value);
      std::memcpy(out, &narrow, 4);
    } else {
      std::memcpy(out, &value, 8);
    }
    return true;
  }
  // Integers; a float-looking packed colour ("4.2108e+06") is read as a number and truncated.
  const double value = std::strtod(token.c_str(), &end);
  if (end == token.c_str() || *end != '\0' || !std::isfinite(value)) return false;
  const double bits = static_cast<double>(field.size * 8);
  const double lowest = field.type == 'U' ? 0.0 : -std::pow(2.0, bits - 1);
  const double highest = (field.type == 'U' ? std::pow(2.0, bits) : std::pow(2.0, bits - 1)) - 1;
  if (value < lowest || value > highest) return false;
  if (field.type == 'U') {
    const auto integer = static_cast<std::uint64_t>(value);
    std::memcpy(out, &integer, field.size);
  } else {
    const auto integer = static_cast<std::int64_t>(value);
    std::memcpy(out, &integer, field.size);
  }
  return true;
}

// The points packed one after the other (header.point_bytes each), whatever the encoding.
bool ReadPcdBody(std::istream& file, const std::string& path, const PcdHeader& header,
                 std::vector<std::uint8_t>* packed, std::string* why) {
  const std::uint64_t n = header.width * header.height;
  const std::uint64_t total = n * header.point_bytes;
  const auto fail = [&](const std::string& problem) {
    *why = path + ": not a valid PCD file: " + problem;
    return false;
  };
  const std::streamoff body = file.tellg();
  file.seekg(0, std::ios::end);
  const std::uint64_t remaining = static_cast<std::uint64_t>(file.tellg() - body);
  file.seekg(body);
  if (header.data == "binary") {
    if (remaining < total) return fail("the binary data is cut short");
    packed->resize(total);
    return static_cast<bool>(
               file.read(reinterpret_cast<char*>(packed->data()), static_cast<std::streamsize>(total))) ||
           fail("the binary data cannot be read");
  }
  if (header.data == "binary_compressed") {
    std::uint32_t sizes[2] = {0, 0};  // compressed, uncompressed
    if (remaining < 8 || !file.read(reinterpret_cast<char*>(sizes), 8) ||
        sizes[0] > remaining - 8 || sizes[1] != total || total > 0xffffffffu) {
      return fail("the compressed data's sizes do not match the header");
    }
    std::vector<std::uint8_t> compressed(sizes[0]);
    std::vector<std::uint8_t> fields_first(total);
    if (!file.read(reinterpret_cast<char*>(compressed.data()), sizes[0]) ||
        pcl::lzfDecompress(compressed.data(), sizes[0], fields_first.data(), sizes[1]) !=
            sizes[1]) {
      return fail("the compressed data does not decompress to the header's size");
    }
    // Compressed PCD stores each field for all points, one field after the other.
    packed->resize(total);
    std::uint64_t field_start = 0;
    for (const PcdField& field : header.fields) {
      const std::uint64_t bytes = field.size * field.count;
      for (std::uint64_t i = 0; i < n; ++i) {
        std::memcpy(packed->data() + i * header.point_bytes + field.offset,
                    fields_first.data() + field_start + i * bytes, bytes);
      }
      field_start += n * bytes;
    }
    return true;
  }
  packed->assign(total, 0);
  std::string line;
  std::uint64_t point = 0;
  while (point < n && std::getline(file, line)) {
    std::istringstream words(line);
    std::vector<std::string> tokens;
    std::string token;
    while (words >> token) tokens.push_back(token);
    if (tokens.empty()) continue;
    std::size_t next = 0;
    for (const PcdField& field : header.fields) {
      for (std::uint64_t e = 0; e < field.count; ++e, ++next) {
        if (next >= tokens.size() ||
            !ParseAsciiValue(tokens[next], field,
                             packed->data() + point * header.point_bytes + field.offset +
                                 e * field.size)) {
          return fail("point " + std::to_string(point) + " has a missing or bad value for " +
                      field.name.substr(0, 32));
        }
      }
    }
    if (next != tokens.size()) return fail("point " + std::to_string(point) + " has extra values");
    ++point;
  }
  return point == n || fail("the ascii data holds " + std::to_string(point) + " of " +
                                std::to_string(n) + " points");
}

// Byte offset of a named 4-byte field, or -1 when the file lacks it (or it has another size).
int FieldOffset(const PcdHeader& header, const std::string& name, bool want_float) {
  for (const PcdField& field : header.fields) {
    if (field.name != name || field.count != 1 || field.size != 4) continue;
    if (want_float ? field.type == 'F' : true) return static_cast<int>(field.offset);
  }
  return -1;
}

template <typename T>
T ReadField(const std::uint8_t* point, int offset) {
  T value;
  std::memcpy(&value, point + offset, sizeof(T));
  return value;
}

// Copies x y z, the packed colour (rgb or rgba: bytes b g r a) and the optional label.
void CopyPoints(const PcdHeader& header, const std::vector<std::uint8_t>& packed,
                const int xyz[3], int color_offset, int label_offset, OrganizedCloud* cloud,
                std::vector<std::uint32_t>* labels) {
  const std::size_t n = static_cast<std::size_t>(header.width * header.height);
  cloud->points_C.resize(n);
  if (color_offset >= 0) cloud->rgb.resize(n);
  if (labels != nullptr && label_offset >= 0) labels->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = packed.data() + i * header.point_bytes;
    Eigen::Vector3f xyz_C(ReadField<float>(p, xyz[0]), ReadField<float>(p, xyz[1]),
                          ReadField<float>(p, xyz[2]));
    // Some writers mark invalid points with z = 0 or a partly-NaN triple; normalise to NaN.
    if (!xyz_C.allFinite() || xyz_C.z() <= 0.f) {
      xyz_C.setConstant(std::numeric_limits<float>::quiet_NaN());
    }
    cloud->points_C[i] = xyz_C;
    if (color_offset >= 0) {
      const auto packed_colour = ReadField<std::uint32_t>(p, color_offset);
      cloud->rgb[i] = {static_cast<std::uint8_t>((packed_colour >> 16) & 0xff),
                       static_cast<std::uint8_t>((packed_colour >> 8) & 0xff),
                       static_cast<std::uint8_t>(packed_colour & 0xff)};
    }
    if (labels != nullptr && label_offset >= 0) {
      (*labels)[i] = ReadField<std::uint32_t>(p, label_offset);
    }
  }
}

}  // namespace

bool LoadOrganizedPcd(const std::string& path, OrganizedCloud* cloud,
                      std::vector<std::uint32_t>* labels, std::string* why) {
  std::string reason;
  if (cloud == nullptr) {
    if (why) *why = "LoadOrganizedPcd: cloud is null";
    return false;
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    if (why) *why = "cannot read PCD file " + path;
    return false;
  }
  PcdHeader header;
  std::vector<std::uint8_t> packed;
  if (!ParsePcdHeader(file, path, &header, &reason) ||
      !ReadPcdBody(file, path, header, &packed, &reason)) {
    if (why) *why = reason;
    return false;
  }
  if (header.height <= 1) {
    if (why) *why = path + " is not organized (height " + std::to_string(header.height) + ")";
    return false;
  }
  const int xyz[3] = {FieldOffset(header, "x", true), FieldOffset(header, "y", true),
                      FieldOffset(header, "z", true)};
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) {
    if (why) *why = path + " lacks float fields x y z";
    return false;
  }
  int color_offset = FieldOffset(header, "rgba", false);
  if (color_offset < 0) color_offset = FieldOffset(header, "rgb", false);
  const int label_offset = FieldOffset(header, "label", false);
  *cloud = OrganizedCloud();
  cloud->width = static_cast<int>(header.width);
  cloud->height = static_cast<int>(header.height);
  if (labels != nullptr) labels->clear();
  CopyPoints(header, packed, xyz, color_offset, label_offset, cloud, labels);
  return true;
}

bool SaveLabelledPcd(const std::string& path, const OrganizedCloud& cloud,
                     const std::vector<std::int32_t>& labels, std::string* why) {
  const size_t n = static_cast<size_t>(cloud.width) * cloud.height;
  if (cloud.width <= 0 || cloud.height <= 0 || cloud.points_C.size() != n) {
    if (why) *why = "SaveLabelledPcd: cloud size does not match width x height";
    return false;
  }
  if (labels.size() != n || (!cloud.rgb.empty() && cloud.rgb.size() != n)) {
    if (why) *why = "SaveLabelledPcd: labels or rgb size differs from the cloud size";
    return false;
  }
  pcl::PointCloud<pcl::PointXYZRGBL> out(cloud.width, cloud.height);
  out.is_dense = false;
  for (size_t i = 0; i < n; ++i) {
    pcl::PointXYZRGBL& p = out[i];
    p.getVector3fMap() = cloud.points_C[i];
    if (!cloud.rgb.empty()) {
      p.r = cloud.rgb[i][0];
      p.g = cloud.rgb[i][1];
      p.b = cloud.rgb[i][2];
    }
    // Segment s is stored as s + 1 so that 0 keeps the mOSD meaning "invalid".
    p.label = labels[i] < 0 ? 0u : static_cast<std::uint32_t>(labels[i]) + 1u;
  }
  if (pcl::io::savePCDFileBinary(path, out) < 0) {
    if (why) *why = "cannot write PCD file " + path;
    return false;
  }
  return true;
}

}  // namespace objmap
