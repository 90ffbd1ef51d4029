#include <gtest/gtest.h>

#include <cmath>

#include "types/coco_classes.h"
#include "types/frame.h"
#include "types/organized_cloud.h"

namespace objmap {
namespace {

TEST(CocoClasses, NamesAndIdsRoundTrip) {
  EXPECT_EQ(CocoClassName(60), "dining table");
  EXPECT_EQ(CocoClassId("dining table"), 60);
  EXPECT_EQ(CocoClassId("dining_table"), 60);
  EXPECT_EQ(CocoClassId("cup"), 41);
  EXPECT_EQ(CocoClassId("tv"), 62);
  EXPECT_EQ(CocoClassId("spaceship"), -1);
  EXPECT_EQ(CocoClassName(80), "");
  EXPECT_EQ(CocoClassFileName(60), "dining_table");
}

TEST(RigidTransform, RejectsNaNAndShear) {
  std::string why;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  EXPECT_TRUE(IsValidRigidTransform(T, &why));
  T(0, 3) = std::nan("");
  EXPECT_FALSE(IsValidRigidTransform(T, &why));
  EXPECT_NE(why.find("NaN"), std::string::npos);
  T = Eigen::Matrix4d::Identity();
  T(0, 1) = 0.5;
  EXPECT_FALSE(IsValidRigidTransform(T, &why));
  EXPECT_NE(why.find("not rigid"), std::string::npos);
}

TEST(Frame, ValidateNamesDepthSizeMismatch) {
  RgbdFrame frame;
  frame.name = "frame-000007";
  frame.depth.width = 320;
  frame.depth.height = 240;
  frame.depth.depth_m.assign(320 * 240, 1.f);
  std::string why;
  EXPECT_FALSE(ValidateFrame(frame, &why));
  EXPECT_NE(why.find("frame-000007"), std::string::npos);
  EXPECT_NE(why.find("320x240"), std::string::npos);
}

TEST(OrganizedCloud, BackProjectsThroughIntrinsics) {
  CameraIntrinsics K;
  K.width = 4;
  K.height = 2;
  K.fx = K.fy = 2.0;
  K.cx = 1.0;
  K.cy = 0.5;
  DepthImage depth;
  depth.width = 4;
  depth.height = 2;
  depth.depth_m = {2.f, 0.f, 2.f, 2.f, 2.f, 2.f, 2.f, 4.f};
  const OrganizedCloud cloud = BackProject(depth, ColorImage{}, K);
  ASSERT_EQ(cloud.size(), 8u);
  EXPECT_FALSE(cloud.IsValid(1));
  EXPECT_TRUE(cloud.IsValid(0));
  EXPECT_NEAR(cloud.points_C[0].x(), -1.0, 1e-6);  // (0 - 1) * 2 / 2
  EXPECT_NEAR(cloud.points_C[0].y(), -0.5, 1e-6);
  EXPECT_NEAR(cloud.points_C[7].x(), 4.0, 1e-6);  // (3 - 1) * 4 / 2
  EXPECT_NEAR(cloud.points_C[7].z(), 4.0, 1e-6);
}

// Colour of the depth image's size is copied; any other size is sampled at the scaled pixel.
// Both must give each point the colour of its pixel.
TEST(OrganizedCloud, BackProjectTakesEachPixelsColour) {
  for (int scale : {1, 2}) {
    DepthImage depth;
    depth.width = 5;
    depth.height = 3;
    depth.depth_m.assign(15, 1.f);
    depth.depth_m[4] = 0.f;  // invalid points keep their colour too
    ColorImage color;
    color.width = 5 * scale;
    color.height = 3 * scale;
    for (int k = 0; k < color.width * color.height * 3; ++k) {
      color.rgb.push_back(static_cast<std::uint8_t>(k * 7 % 251));
    }
    CameraIntrinsics K;
    K.width = 5;
    K.height = 3;
    const OrganizedCloud cloud = BackProject(depth, color, K);
    ASSERT_EQ(cloud.rgb.size(), 15u);
    for (int v = 0; v < 3; ++v) {
      for (int u = 0; u < 5; ++u) {
        const std::size_t c = (static_cast<std::size_t>(v * scale) * color.width + u * scale) * 3;
        const std::array<std::uint8_t, 3> expected = {color.rgb[c], color.rgb[c + 1],
                                                      color.rgb[c + 2]};
        EXPECT_EQ(cloud.rgb[v * 5 + u], expected)
            << "scale " << scale << " pixel " << u << "," << v;
      }
    }
  }
}

}  // namespace
}  // namespace objmap
