// PCD round trip through SaveLabelledPcd / LoadOrganizedPcd, PLY layout, and error reporting.
#include "pointcloud_io/pointcloud_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_data.h"

namespace objmap {
namespace {

OrganizedCloud SmallCloud(std::vector<std::int32_t>* labels) {
  OrganizedCloud cloud;
  cloud.width = 8;
  cloud.height = 6;
  for (int i = 0; i < 48; ++i) {
    const bool invalid = i % 7 == 3;
    cloud.points_C.push_back(invalid ? Eigen::Vector3f::Constant(std::nanf(""))
                                     : Eigen::Vector3f(0.01f * i, -0.02f * i, 1.f + 0.001f * i));
    cloud.rgb.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(200 - i),
                         static_cast<std::uint8_t>(3 * i)});
    labels->push_back(invalid ? -1 : i % 5);
  }
  return cloud;
}

TEST(PointcloudIoTest, LabelledPcdRoundTrip) {
  std::vector<std::int32_t> labels;
  const OrganizedCloud cloud = SmallCloud(&labels);
  const std::string path = ::testing::TempDir() + "/objmap_roundtrip.pcd";
  std::string why;
  ASSERT_TRUE(SaveLabelledPcd(path, cloud, labels, &why)) << why;
  OrganizedCloud loaded;
  std::vector<std::uint32_t> loaded_labels;
  ASSERT_TRUE(LoadOrganizedPcd(path, &loaded, &loaded_labels, &why)) << why;
  ASSERT_EQ(loaded.width, 8);
  ASSERT_EQ(loaded.height, 6);
  ASSERT_EQ(loaded.rgb.size(), 48u);
  ASSERT_EQ(loaded_labels.size(), 48u);
  for (int i = 0; i < 48; ++i) {
    EXPECT_EQ(loaded.IsValid(i), cloud.IsValid(i)) << i;
    if (cloud.IsValid(i)) {
      EXPECT_EQ(loaded.points_C[i], cloud.points_C[i]) << i;
    }
    EXPECT_EQ(loaded.rgb[i], cloud.rgb[i]) << i;
    EXPECT_EQ(loaded_labels[i], static_cast<std::uint32_t>(labels[i] + 1)) << i;
  }
  std::filesystem::remove(path);
}

TEST(PointcloudIoTest, BadInputIsReported) {
  std::vector<std::int32_t> labels;
  const OrganizedCloud cloud = SmallCloud(&labels);
  std::string why;
  labels.pop_back();
  EXPECT_FALSE(SaveLabelledPcd(::testing::TempDir() + "/x.pcd", cloud, labels, &why));
  EXPECT_NE(why.find("labels"), std::string::npos) << why;
  OrganizedCloud loaded;
  EXPECT_FALSE(LoadOrganizedPcd("/nonexistent/cloud.pcd", &loaded, nullptr, &why));
  EXPECT_NE(why.find("/nonexistent/cloud.pcd"), std::string::npos) << why;
}

TEST(PointcloudIoTest, PlyIsBinaryLittleEndianWithColours) {
  const std::vector<Eigen::Vector3f> points = {{1.f, 2.f, 3.f}, {-1.f, 0.5f, 4.f}};
  const std::vector<std::array<std::uint8_t, 3>> colors = {{{10, 20, 30}}, {{40, 50, 60}}};
  const std::string path = ::testing::TempDir() + "/objmap_points.ply";
  std::string why;
  ASSERT_TRUE(WritePly(path, points, colors, &why)) << why;
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  const std::string end = "end_header\n";
  const size_t body = bytes.find(end);
  ASSERT_NE(body, std::string::npos);
  EXPECT_NE(bytes.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(bytes.find("element vertex 2"), std::string::npos);
  ASSERT_EQ(bytes.size(), body + end.size() + 2 * 15);
  float second_x = 0.f;
  std::memcpy(&second_x, bytes.data() + body + end.size() + 15, 4);
  EXPECT_EQ(second_x, -1.f);
  EXPECT_EQ(static_cast<std::uint8_t>(bytes[body + end.size() + 15 + 14]), 60);
  EXPECT_FALSE(WritePly(path, points, {{{1, 2, 3}}}, &why));
  std::filesystem::remove(path);
}

TEST(PointcloudIoTest, ReadsMosdCloudWithLabels) {
  const std::string path = testing::SharedDataPath("mosd-learn/learn0.pcd");
  OBJMAP_REQUIRE_PATH(path);
  OrganizedCloud cloud;
  std::vector<std::uint32_t> labels;
  std::string why;
  ASSERT_TRUE(LoadOrganizedPcd(path, &cloud, &labels, &why)) << why;
  EXPECT_EQ(cloud.width, 640);
  EXPECT_EQ(cloud.height, 480);
  ASSERT_EQ(labels.size(), cloud.size());
  int valid = 0, invalid_with_label0 = 0, objects = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    valid += cloud.IsValid(static_cast<int>(i)) ? 1 : 0;
    invalid_with_label0 += !cloud.IsValid(static_cast<int>(i)) && labels[i] == 0 ? 1 : 0;
    objects += labels[i] >= 20 ? 1 : 0;
  }
  EXPECT_GT(valid, 10000);
  EXPECT_EQ(invalid_with_label0, static_cast<int>(cloud.size()) - valid);
  EXPECT_GT(objects, 1000);
}

}  // namespace
}  // namespace objmap
