// Request conversions of the gRPC service: poses, detections, images. No server involved.
#include "grpc_service/conversions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "types/image_header.h"
#include "grpc_service/keyframe_conversions.h"
#include "types/coco_classes.h"

namespace objmap::grpc_service {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Encode(const cv::Mat& image, const char* extension) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(extension, image, bytes));
  return std::string(bytes.begin(), bytes.end());
}

// A BGR image whose pixel (u, v) is (b, g, r) = (u, v, 200): channel order is visible.
cv::Mat GradientBgr(int width, int height) {
  cv::Mat bgr(height, width, CV_8UC3);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      bgr.at<cv::Vec3b>(v, u) = {static_cast<std::uint8_t>(u), static_cast<std::uint8_t>(v), 200};
    }
  }
  return bgr;
}

TEST(PoseConversion, RoundTripsAndNormalizesNearlyUnitQuaternions) {
  const Eigen::Isometry3d T = Eigen::Translation3d(1.5, -2.0, 0.25) *
                              Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized());
  v1::Pose pose = PoseToProto(T);
  Eigen::Isometry3d back;
  std::string why;
  ASSERT_TRUE(PoseFromProto(pose, "T_W_C", &back, &why)) << why;
  EXPECT_TRUE(back.matrix().isApprox(T.matrix(), 1e-12));

  pose.set_qw(pose.qw() * 1.0005);  // within 1e-3 of unit norm: normalized
  ASSERT_TRUE(PoseFromProto(pose, "T_W_C", &back, &why)) << why;
  EXPECT_NEAR((back.linear() * back.linear().transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0,
              1e-12);
}

TEST(PoseConversion, RejectsNonUnitAndNonFiniteQuaternionsNamingTheField) {
  v1::Pose pose;  // unset: all zero
  Eigen::Isometry3d T;
  std::string why;
  EXPECT_FALSE(PoseFromProto(pose, "T_W_C", &T, &why));
  EXPECT_NE(why.find("T_W_C.q"), std::string::npos) << why;
  EXPECT_NE(why.find("norm 0"), std::string::npos) << why;

  pose.set_qw(1.01);
  EXPECT_FALSE(PoseFromProto(pose, "poses[2].T_W_C", &T, &why));
  EXPECT_EQ(why.rfind("poses[2].T_W_C.q", 0), 0u) << why;

  pose.set_qw(1.0);
  pose.set_qy(kNaN);
  EXPECT_FALSE(PoseFromProto(pose, "T_W_C", &T, &why));
  EXPECT_EQ(why.rfind("T_W_C.qy is nan", 0), 0u) << why;

  pose.set_qy(0.0);
  pose.mutable_translation()->set_z(std::numeric_limits<double>::infinity());
  EXPECT_FALSE(PoseFromProto(pose, "T_W_C", &T, &why));
  EXPECT_EQ(why.rfind("T_W_C.translation.z is inf", 0), 0u) << why;
}

TEST(DetectionConversion, ClassByNameOrIdAndTheNameWins) {
  v1::Detection proto;
  proto.set_x_min(1);
  proto.set_y_min(2);
  proto.set_x_max(30);
  proto.set_y_max(40);
  proto.set_score(0.5f);
  proto.set_class_id(3);
  Detection detection;
  std::string why;
  ASSERT_TRUE(DetectionFromProto(proto, "detections[0]", &detection, &why)) << why;
  EXPECT_EQ(detection.class_id, 3);
  EXPECT_FLOAT_EQ(detection.box.x_max, 30.f);
  EXPECT_FLOAT_EQ(detection.score, 0.5f);

  proto.set_class_name("dining table");
  ASSERT_TRUE(DetectionFromProto(proto, "detections[0]", &detection, &why)) << why;
  EXPECT_EQ(detection.class_id, CocoClassId("dining table"));
}

TEST(DetectionConversion, RejectsUnknownClassesScoresAndEmptyBoxes) {
  v1::Detection proto;
  proto.set_x_max(10);
  proto.set_y_max(10);
  proto.set_score(0.5f);
  proto.set_class_name("unicorn");
  Detection detection;
  std::string why;
  EXPECT_FALSE(DetectionFromProto(proto, "detections[3]", &detection, &why));
  EXPECT_EQ(why, "detections[3].class_name 'unicorn' is not a COCO class");

  proto.clear_class_name();
  proto.set_class_id(80);
  EXPECT_FALSE(DetectionFromProto(proto, "detections[1]", &detection, &why));
  EXPECT_EQ(why.rfind("detections[1].class_id 80", 0), 0u) << why;

  proto.set_class_id(0);
  proto.set_score(1.5f);
  EXPECT_FALSE(DetectionFromProto(proto, "detections[1]", &detection, &why));
  EXPECT_EQ(why.rfind("detections[1].score", 0), 0u) << why;

  proto.set_score(std::numeric_limits<float>::quiet_NaN());
  EXPECT_FALSE(DetectionFromProto(proto, "detections[1]", &detection, &why));

  proto.set_score(0.5f);
  proto.set_x_max(0.f);  // x_min == x_max
  EXPECT_FALSE(DetectionFromProto(proto, "detections[1]", &detection, &why));
  EXPECT_NE(why.find("x_min < x_max"), std::string::npos) << why;
}

TEST(StatusConversion, EveryCodeMapsToItsGrpcCode) {
  const std::pair<StatusCode, grpc::StatusCode> cases[] = {
      {StatusCode::kOk, grpc::StatusCode::OK},
      {StatusCode::kInvalidArgument, grpc::StatusCode::INVALID_ARGUMENT},
      {StatusCode::kNotFound, grpc::StatusCode::NOT_FOUND},
      {StatusCode::kResourceExhausted, grpc::StatusCode::RESOURCE_EXHAUSTED},
      {StatusCode::kUnavailable, grpc::StatusCode::UNAVAILABLE},
      {StatusCode::kInternal, grpc::StatusCode::INTERNAL}};
  for (const auto& [code, grpc_code] : cases) {
    const grpc::Status status = ToGrpcStatus({code, "message"});
    EXPECT_EQ(status.error_code(), grpc_code);
    if (code != StatusCode::kOk) {
      EXPECT_EQ(status.error_message(), "message");
    }
  }
}

TEST(ObjectConversion, ModelGoesOutAsLittleEndianFloatTriplesAndRgb) {
  auto model = std::make_shared<ColoredPoints>();
  model->points = {{1.f, -2.f, 0.5f}, {0.25f, 3.f, -1.f}};
  model->colors = {{{10, 20, 30}}, {{40, 50, 60}}};
  ObjectView view;
  view.id = 7;
  view.class_id = CocoClassId("cup");
  view.scores = {{view.class_id, 2.5f}, {CocoClassId("bowl"), 0.5f}};
  view.model_W = model;
  v1::Object object;
  ObjectToProto(view, /*include_model=*/false, &object);
  EXPECT_EQ(object.class_name(), "cup");
  EXPECT_EQ(object.num_points(), 0);
  ASSERT_EQ(object.scores_size(), 2);
  EXPECT_EQ(object.scores(1).class_name(), "bowl");

  ObjectToProto(view, /*include_model=*/true, &object);
  ASSERT_EQ(object.num_points(), 2);
  ASSERT_EQ(object.points_xyz().size(), 24u);
  ASSERT_EQ(object.points_rgb().size(), 6u);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(object.points_xyz().data());
  for (int i = 0; i < 6; ++i) {
    const std::uint32_t bits = bytes[4 * i] | bytes[4 * i + 1] << 8 | bytes[4 * i + 2] << 16 |
                               std::uint32_t(bytes[4 * i + 3]) << 24;
    float value;
    std::memcpy(&value, &bits, sizeof(value));
    EXPECT_EQ(value, model->points[i / 3][i % 3]);
  }
  EXPECT_EQ(static_cast<std::uint8_t>(object.points_rgb()[4]), 50);
}

TEST(ImageHeader, ReadsPngAndJpegSizesAndRefusesOtherBytes) {
  int width = 0;
  int height = 0;
  ASSERT_TRUE(ReadPngSize(Encode(GradientBgr(37, 21), ".png"), &width, &height));
  EXPECT_EQ(width, 37);
  EXPECT_EQ(height, 21);
  ASSERT_TRUE(ReadJpegSize(Encode(GradientBgr(41, 19), ".jpg"), &width, &height));
  EXPECT_EQ(width, 41);
  EXPECT_EQ(height, 19);
  EXPECT_FALSE(ReadPngSize(Encode(GradientBgr(8, 8), ".jpg"), &width, &height));
  EXPECT_FALSE(ReadJpegSize(Encode(GradientBgr(8, 8), ".png"), &width, &height));
  EXPECT_FALSE(ReadJpegSize(std::string("\xFF\xD8\xFF", 3), &width, &height));
}

}  // namespace
}  // namespace objmap::grpc_service
