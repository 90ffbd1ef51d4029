#include "pointcloud_io/pointcloud_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cstring>
#include <limits>

namespace objmap {
namespace {

// Byte offset of a named 4-byte field, or -1 when the file lacks it (or it has another size).
int FieldOffset(const pcl::PCLPointCloud2& blob, const std::string& name, bool want_float) {
  for (const auto& field : blob.fields) {
    if (field.name != name || field.count != 1) continue;
    const bool is_float = field.datatype == pcl::PCLPointField::FLOAT32;
    const bool is_u32 =
        field.datatype == pcl::PCLPointField::UINT32 || field.datatype == pcl::PCLPointField::INT32;
    if (want_float ? is_float : (is_u32 || is_float)) return static_cast<int>(field.offset);
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
void CopyPoints(const pcl::PCLPointCloud2& blob, const int xyz[3], int color_offset,
                int label_offset, OrganizedCloud* cloud, std::vector<std::uint32_t>* labels) {
  const size_t n = static_cast<size_t>(blob.width) * blob.height;
  cloud->points_C.resize(n);
  if (color_offset >= 0) cloud->rgb.resize(n);
  if (labels != nullptr && label_offset >= 0) labels->resize(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t row = i / blob.width;
    const size_t col = i % blob.width;
    const std::uint8_t* p = blob.data.data() + row * blob.row_step + col * blob.point_step;
    Eigen::Vector3f xyz_C(ReadField<float>(p, xyz[0]), ReadField<float>(p, xyz[1]),
                          ReadField<float>(p, xyz[2]));
    // Some writers mark invalid points with z = 0 or a partly-NaN triple; normalise to NaN.
    if (!xyz_C.allFinite() || xyz_C.z() <= 0.f) {
      xyz_C.setConstant(std::numeric_limits<float>::quiet_NaN());
    }
    cloud->points_C[i] = xyz_C;
    if (color_offset >= 0) {
      const auto packed = ReadField<std::uint32_t>(p, color_offset);
      cloud->rgb[i] = {static_cast<std::uint8_t>((packed >> 16) & 0xff),
                       static_cast<std::uint8_t>((packed >> 8) & 0xff),
                       static_cast<std::uint8_t>(packed & 0xff)};
    }
    if (labels != nullptr && label_offset >= 0) {
      (*labels)[i] = ReadField<std::uint32_t>(p, label_offset);
    }
  }
}

}  // namespace

bool LoadOrganizedPcd(const std::string& path, OrganizedCloud* cloud,
                      std::vector<std::uint32_t>* labels, std::string* why) {
  if (cloud == nullptr) {
    if (why) *why = "LoadOrganizedPcd: cloud is null";
    return false;
  }
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  if (reader.read(path, blob) < 0) {
    if (why) *why = "cannot read PCD file " + path;
    return false;
  }
  if (blob.height <= 1 || blob.width == 0) {
    if (why) *why = path + " is not organized (height " + std::to_string(blob.height) + ")";
    return false;
  }
  const int xyz[3] = {FieldOffset(blob, "x", true), FieldOffset(blob, "y", true),
                      FieldOffset(blob, "z", true)};
  if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) {
    if (why) *why = path + " lacks float fields x y z";
    return false;
  }
  int color_offset = FieldOffset(blob, "rgba", false);
  if (color_offset < 0) color_offset = FieldOffset(blob, "rgb", false);
  const int label_offset = FieldOffset(blob, "label", false);
  *cloud = OrganizedCloud();
  cloud->width = static_cast<int>(blob.width);
  cloud->height = static_cast<int>(blob.height);
  if (labels != nullptr) labels->clear();
  CopyPoints(blob, xyz, color_offset, label_offset, cloud, labels);
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
