// PCD round trip through SaveLabelledPcd / LoadOrganizedPcd, PLY layout, and error reporting.
#include "pointcloud_io/pointcloud_io.h"

#include <gtest/gtest.h>

#include <array>
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

// Files that crashed PCL's reader (found by tests/fuzz/pcd_reader_fuzzer.cc) are refused with
// a reason; an ASCII file written by hand reads as its binary twin does.
TEST(PointcloudIoTest, MalformedPcdFilesAreRefusedNotCrashedOn) {
  const std::string dir = ::testing::TempDir();
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name, std::ios::binary) << text;
    return dir + "/" + name;
  };
  const std::string header =
      "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgba label\nSIZE 4 4 4 4 4\nTYPE F F F U U\n"
      "COUNT 1 1 1 1 1\nWIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\n";
  const std::string ascii_body =
      "DATA ascii\n0.1 0.2 1 4278190335 1\n0.2 0.2 1 4278190335 1\nnan nan nan 0 0\n"
      "0.2 0.3 1.1 4278255360 2\n";
  OrganizedCloud cloud;
  std::vector<std::uint32_t> labels;
  std::string why;
  ASSERT_TRUE(LoadOrganizedPcd(write("ok.pcd", header + ascii_body), &cloud, &labels, &why))
      << why;
  EXPECT_EQ(cloud.width, 2);
  EXPECT_EQ(cloud.height, 2);
  EXPECT_FALSE(cloud.IsValid(2));
  EXPECT_EQ(cloud.points_C[3], Eigen::Vector3f(0.2f, 0.3f, 1.1f));
  EXPECT_EQ(cloud.rgb[3], (std::array<std::uint8_t, 3>{0, 255, 0}));  // 0xFF00FF00: a ff, r 00, g ff, b 00
  EXPECT_EQ(labels, (std::vector<std::uint32_t>{1, 1, 0, 2}));

  std::vector<std::int32_t> small_labels;
  const OrganizedCloud small = SmallCloud(&small_labels);
  ASSERT_TRUE(SaveLabelledPcd(dir + "/binary.pcd", small, small_labels, &why)) << why;
  std::ifstream binary_file(dir + "/binary.pcd", std::ios::binary);
  const std::string binary((std::istreambuf_iterator<char>(binary_file)),
                           std::istreambuf_iterator<char>());
  const std::pair<std::string, std::string> bad[] = {
      {"", "no DATA line"},
      {"# .PCD v0.7\nPOIN\x84TS 4\n" + header.substr(12) + ascii_body, "control byte"},
      {"+ .PCD v0.7\n" + header + ascii_body, "unknown header line '+'"},
      {header + "WIDTH 2\n" + ascii_body, "header key WIDTH twice"},
      {header.substr(0, header.find("POINTS")) + ascii_body, "WIDTH x HEIGHT must equal POINTS"},
      {header + "DATA ascii\n0.1 0.2 1 4278190335 1\n0.2 1\n", "point 1 has a missing"},
      {header + "DATA ascii\n0.1 0.2 1 4278190335 1\n", "holds 1 of 4 points"},
      {header + "DATA ascii\n0.1 0.2 1 -5 1\n", "bad value for rgba"},
      {binary.substr(0, binary.size() - 10), "the binary data is cut short"},
      {header.substr(0, header.find("SIZE")) + "SIZE 2 4 4 4 4\n" +
           header.substr(header.find("TYPE")) + ascii_body,
       "field x has an unknown size"},
  };
  for (const auto& [text, reason] : bad) {
    EXPECT_FALSE(LoadOrganizedPcd(write("bad.pcd", text), &cloud, &labels, &why)) << reason;
    EXPECT_NE(why.find(reason), std::string::npos) << why;
  }
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
