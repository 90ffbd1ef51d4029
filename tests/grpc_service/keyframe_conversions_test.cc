// Image decoding and AddKeyframeRequest -> RgbdFrame: encodings, sizes, error messages.
#include "grpc_service/keyframe_conversions.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "grpc_service/conversions.h"

namespace objmap::grpc_service {
namespace {

CameraIntrinsics SmallIntrinsics(int width = 8, int height = 6) {
  CameraIntrinsics K;
  K.width = width;
  K.height = height;
  K.fx = K.fy = 10.0;
  K.cx = width / 2.0;
  K.cy = height / 2.0;
  return K;
}

std::string Encode(const cv::Mat& image, const char* extension) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(extension, image, bytes));
  return std::string(bytes.begin(), bytes.end());
}

v1::Image MakeImage(v1::Image::Encoding encoding, std::string data, int width = 0, int height = 0) {
  v1::Image image;
  image.set_encoding(encoding);
  image.set_data(std::move(data));
  image.set_width(width);
  image.set_height(height);
  return image;
}

// Pixel (u, v) is (b, g, r) = (u, v, 200) in OpenCV's order: channel swaps are visible.
cv::Mat GradientBgr(int width, int height) {
  cv::Mat bgr(height, width, CV_8UC3);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      bgr.at<cv::Vec3b>(v, u) = {static_cast<std::uint8_t>(u), static_cast<std::uint8_t>(v), 200};
    }
  }
  return bgr;
}

cv::Mat DepthUnits(int width, int height) {
  cv::Mat units(height, width, CV_16UC1);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) units.at<std::uint16_t>(v, u) = 1000 + 10 * u + v;
  }
  return units;
}

std::string LittleEndian(const std::vector<std::uint16_t>& values) {
  std::string bytes;
  for (std::uint16_t value : values) {
    bytes.push_back(static_cast<char>(value & 0xff));
    bytes.push_back(static_cast<char>(value >> 8));
  }
  return bytes;
}

TEST(ColorDecoding, PngComesOutAsRgb) {
  const CameraIntrinsics K = SmallIntrinsics();
  ColorImage color;
  std::string why;
  ASSERT_TRUE(DecodeColorImage(MakeImage(v1::Image::PNG, Encode(GradientBgr(8, 6), ".png")), K,
                               &color, &why))
      << why;
  ASSERT_EQ(color.rgb.size(), 8u * 6 * 3);
  const std::size_t pixel = (2 * 8 + 5) * 3;  // (u, v) = (5, 2)
  EXPECT_EQ(color.rgb[pixel], 200);           // red was OpenCV's third channel
  EXPECT_EQ(color.rgb[pixel + 1], 2);
  EXPECT_EQ(color.rgb[pixel + 2], 5);
}

TEST(ColorDecoding, SizeMismatchNamesColorAndBothSizes) {
  ColorImage color;
  std::string why;
  EXPECT_FALSE(DecodeColorImage(MakeImage(v1::Image::JPEG, Encode(GradientBgr(16, 12), ".jpg")),
                                SmallIntrinsics(), &color, &why));
  EXPECT_EQ(why, "color is 16x12 but the intrinsics say 8x6");

  EXPECT_FALSE(DecodeColorImage(MakeImage(v1::Image::RAW_RGB8, std::string(100, '\0'), 8, 6),
                                SmallIntrinsics(), &color, &why));
  EXPECT_NE(why.find("color.data has 100 bytes"), std::string::npos) << why;
  EXPECT_NE(why.find("144"), std::string::npos) << why;
}

TEST(ColorDecoding, RefusesGarbageAndDepthEncodings) {
  ColorImage color;
  std::string why;
  EXPECT_FALSE(DecodeColorImage(MakeImage(v1::Image::PNG, "not a png at all, really"),
                                SmallIntrinsics(), &color, &why));
  EXPECT_NE(why.find("is not a PNG image"), std::string::npos) << why;
  // A valid header followed by garbage: the decoder, not the header check, refuses it.
  std::string truncated = Encode(GradientBgr(8, 6), ".png").substr(0, 40);
  EXPECT_FALSE(
      DecodeColorImage(MakeImage(v1::Image::PNG, truncated), SmallIntrinsics(), &color, &why));
  EXPECT_NE(why.find("color.data could not be decoded"), std::string::npos) << why;
  EXPECT_FALSE(
      DecodeColorImage(MakeImage(v1::Image::RAW_DEPTH_U16, ""), SmallIntrinsics(), &color, &why));
  EXPECT_NE(why.find("not a colour encoding"), std::string::npos) << why;
}

// A JPEG cut short decodes without an error (the decoder greys the missing rows), so the end
// marker is checked; a whole JPEG with padding after its end still decodes.
TEST(ColorDecoding, ATruncatedJpegIsRefused) {
  const CameraIntrinsics K = SmallIntrinsics(64, 48);
  const std::string jpeg = Encode(GradientBgr(64, 48), ".jpg");
  ColorImage color;
  std::string why;
  ASSERT_TRUE(DecodeColorImage(MakeImage(v1::Image::JPEG, jpeg), K, &color, &why)) << why;
  ASSERT_TRUE(DecodeColorImage(MakeImage(v1::Image::JPEG, jpeg + std::string(8, '\0')), K, &color,
                               &why))
      << why;
  for (const std::size_t cut : {std::size_t{2}, jpeg.size() / 3}) {
    EXPECT_FALSE(DecodeColorImage(MakeImage(v1::Image::JPEG, jpeg.substr(0, jpeg.size() - cut)), K,
                                  &color, &why))
        << "cut " << cut;
    EXPECT_NE(why.find("truncated JPEG"), std::string::npos) << why;
  }
}

TEST(DepthDecoding, SixteenBitPngTimesDepthScale) {
  const CameraIntrinsics K = SmallIntrinsics();
  v1::Image image = MakeImage(v1::Image::PNG, Encode(DepthUnits(8, 6), ".png"));
  DepthImage depth;
  std::string why;
  ASSERT_TRUE(DecodeDepthImage(image, K, &depth, &why)) << why;
  EXPECT_FLOAT_EQ(depth.depth_m[2 * 8 + 5], 1.052f);  // default 0.001 m per unit
  image.set_depth_scale(0.0002);                      // TUM: 5000 units per metre
  ASSERT_TRUE(DecodeDepthImage(image, K, &depth, &why)) << why;
  EXPECT_FLOAT_EQ(depth.depth_m[2 * 8 + 5], 1052 * 0.0002f);

  image.set_depth_scale(-1.0);
  EXPECT_FALSE(DecodeDepthImage(image, K, &depth, &why));
  EXPECT_EQ(why.rfind("depth.depth_scale", 0), 0u) << why;
}

TEST(DepthDecoding, EightBitPngIsRefused) {
  cv::Mat gray(6, 8, CV_8UC1, cv::Scalar(7));
  DepthImage depth;
  std::string why;
  EXPECT_FALSE(DecodeDepthImage(MakeImage(v1::Image::PNG, Encode(gray, ".png")), SmallIntrinsics(),
                                &depth, &why));
  EXPECT_NE(why.find("8-bit"), std::string::npos) << why;
}

TEST(DepthDecoding, RawEncodingsCheckTheirByteCounts) {
  const CameraIntrinsics K = SmallIntrinsics(2, 2);
  DepthImage depth;
  std::string why;
  ASSERT_TRUE(DecodeDepthImage(
      MakeImage(v1::Image::RAW_DEPTH_U16, LittleEndian({0, 1000, 2500, 65535}), 2, 2), K, &depth,
      &why))
      << why;
  EXPECT_EQ(depth.depth_m, (std::vector<float>{0.f, 1.f, 2.5f, 65.535f}));

  const float values[] = {1.25f, std::numeric_limits<float>::quiet_NaN(), -3.f,
                          std::numeric_limits<float>::infinity()};
  std::string bytes(sizeof(values), '\0');
  std::memcpy(bytes.data(), values, sizeof(values));  // x86 and ARM are little-endian
  ASSERT_TRUE(DecodeDepthImage(MakeImage(v1::Image::RAW_DEPTH_F32, bytes, 2, 2), K, &depth, &why))
      << why;
  EXPECT_EQ(depth.depth_m, (std::vector<float>{1.25f, 0.f, 0.f, 0.f}));

  EXPECT_FALSE(DecodeDepthImage(MakeImage(v1::Image::RAW_DEPTH_F32, bytes.substr(1), 2, 2), K,
                                &depth, &why));
  EXPECT_EQ(why, "depth.data has 15 bytes but 2x2 x 4 needs 16");
  EXPECT_FALSE(DecodeDepthImage(MakeImage(v1::Image::RAW_DEPTH_F32, bytes, 4, 1), K, &depth, &why));
  EXPECT_EQ(why, "depth.width/height are 4x1 but the intrinsics say 2x2");
  EXPECT_FALSE(DecodeDepthImage(MakeImage(v1::Image::JPEG, bytes), K, &depth, &why));
  EXPECT_NE(why.find("not a depth encoding"), std::string::npos) << why;
}

TEST(DepthDecoding, HugeImagesAreRefusedBeforeDecoding) {
  DepthImage depth;
  std::string why;
  EXPECT_FALSE(DecodeDepthImage(MakeImage(v1::Image::RAW_DEPTH_U16, "", 100000, 100000),
                                SmallIntrinsics(100000, 100000), &depth, &why));
  EXPECT_NE(why.find("exceeds the largest image"), std::string::npos) << why;
}

class FrameFromRequestTest : public ::testing::Test {
 protected:
  FrameFromRequestTest() { Reset(); }

  // A valid request of an 8x6 frame without detections.
  void Reset() {
    request_.Clear();
    const CameraIntrinsics K = SmallIntrinsics();
    auto* intrinsics = request_.mutable_intrinsics();
    intrinsics->set_width(K.width);
    intrinsics->set_height(K.height);
    intrinsics->set_fx(K.fx);
    intrinsics->set_fy(K.fy);
    intrinsics->set_cx(K.cx);
    intrinsics->set_cy(K.cy);
    *request_.mutable_t_w_c() = PoseToProto(Eigen::Isometry3d(Eigen::Translation3d(1, 2, 3)));
    *request_.mutable_color() = MakeImage(v1::Image::PNG, Encode(GradientBgr(8, 6), ".png"));
    *request_.mutable_depth() = MakeImage(v1::Image::PNG, Encode(DepthUnits(8, 6), ".png"));
    request_.set_stamp(12.5);
    request_.set_name("frame-1");
  }

  v1::Detection* AddCup() {
    v1::Detection* detection = request_.add_detections();
    detection->set_class_name("cup");
    detection->set_x_max(4);
    detection->set_y_max(4);
    detection->set_score(0.9f);
    return detection;
  }

  bool Convert() {
    return FrameFromRequest(request_, limits_, pose_optional_, &frame_, &detections_, &code_,
                            &why_);
  }

  v1::AddKeyframeRequest request_;
  RequestLimits limits_;
  bool pose_optional_ = false;
  RgbdFrame frame_;
  std::optional<std::vector<Detection>> detections_;
  grpc::StatusCode code_ = grpc::StatusCode::OK;
  std::string why_;
};

TEST_F(FrameFromRequestTest, AnUnsetPoseIsRefusedUnlessTheServerEstimatesPoses) {
  request_.clear_t_w_c();
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(why_.find("(pose unset?)"), std::string::npos) << why_;
  pose_optional_ = true;
  ASSERT_TRUE(Convert()) << why_;
  EXPECT_TRUE(frame_.T_W_C.isApprox(Eigen::Isometry3d::Identity()));
  // A pose that is there is still checked.
  request_.mutable_t_w_c()->set_qw(std::nan(""));
  EXPECT_FALSE(Convert());
  EXPECT_NE(why_.find("T_W_C.qw"), std::string::npos) << why_;
}

TEST_F(FrameFromRequestTest, DetectionsOnlyWhenGiven) {
  ASSERT_TRUE(Convert()) << why_;
  EXPECT_FALSE(detections_.has_value());  // the server's detector runs
  EXPECT_EQ(frame_.name, "frame-1");
  EXPECT_DOUBLE_EQ(frame_.stamp_s, 12.5);
  EXPECT_TRUE(frame_.T_W_C.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE(ValidateFrame(frame_, &why_)) << why_;

  request_.set_detections_given(true);
  ASSERT_TRUE(Convert()) << why_;
  ASSERT_TRUE(detections_.has_value());
  EXPECT_TRUE(detections_->empty());  // given, and none: no objects, no detector

  AddCup();
  request_.set_detections_given(false);
  EXPECT_FALSE(Convert());
  EXPECT_NE(why_.find("detections_given is false"), std::string::npos) << why_;
}

TEST_F(FrameFromRequestTest, ErrorsNameTheField) {
  request_.set_detections_given(true);
  AddCup();
  AddCup()->set_class_name("unicorn");
  EXPECT_FALSE(Convert());
  EXPECT_EQ(why_, "detections[1].class_name 'unicorn' is not a COCO class");

  request_.mutable_t_w_c()->set_qw(0.0);
  EXPECT_FALSE(Convert());
  EXPECT_EQ(why_.rfind("T_W_C.q", 0), 0u) << why_;

  request_.clear_intrinsics();
  EXPECT_FALSE(Convert());
  EXPECT_EQ(why_.rfind("intrinsics", 0), 0u) << why_;
}

// Limits are RESOURCE_EXHAUSTED, name the field and the limit, and never quote the input.
TEST_F(FrameFromRequestTest, LimitsNameTheFieldAndTheLimit) {
  ASSERT_TRUE(Convert()) << why_;
  request_.set_detections_given(true);
  limits_.max_detections_per_keyframe = 2;
  for (int i = 0; i < 3; ++i) AddCup();
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(why_,
            "detections has 3 entries; the server takes at most 2 per keyframe "
            "(server.max_detections_per_keyframe)");
  request_.mutable_detections()->RemoveLast();
  ASSERT_TRUE(Convert()) << why_;

  request_.mutable_detections(1)->set_class_name(std::string(20000, 'x'));
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(why_,
            "detections[1].class_name is 20000 bytes; the server takes at most 1024 "
            "(server.max_string_bytes)");
  request_.mutable_detections(1)->set_class_name(std::string(500, 'x'));
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_LT(why_.size(), 200u) << "the unknown class is quoted shortened";
  request_.mutable_detections(1)->set_class_name("cup");

  request_.set_name(std::string(2000, 'n'));
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(why_.rfind("name is 2000 bytes", 0), 0u) << why_;
  request_.set_name("frame-1");

  limits_.max_image_pixels = 47;  // the frames are 8x6
  EXPECT_FALSE(Convert());
  EXPECT_EQ(code_, grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(why_,
            "intrinsics: 8x6 is 48 pixels; the server decodes at most 47 (server.max_image_pixels)");
}

// Finite is not enough: magnitudes that overflow pixel, voxel or float arithmetic are refused
// with the field and the bound, and depths out of any sensor's range are no measurement.
TEST_F(FrameFromRequestTest, MagnitudesBeyondAnyCameraAreRefused) {
  const auto refused = [&](const char* what, const std::string& field) {
    EXPECT_FALSE(Convert()) << what;
    EXPECT_EQ(code_, grpc::StatusCode::INVALID_ARGUMENT) << what;
    EXPECT_NE(why_.find(field), std::string::npos) << what << ": " << why_;
    Reset();
  };
  request_.mutable_intrinsics()->set_fy(3.4e38);
  refused("fy 3.4e38", "fy 3.4e+38");
  request_.mutable_intrinsics()->set_fx(1e300);
  refused("fx 1e300", "fx 1e+300");
  request_.mutable_intrinsics()->set_fx(0.5);
  refused("fx 0.5", "must lie in [1, 100000]");
  request_.mutable_intrinsics()->set_cx(1e300);
  refused("cx 1e300", "principal point");
  request_.mutable_t_w_c()->mutable_translation()->set_y(1e300);
  refused("translation 1e300", "T_W_C.translation.y is 1e+300 m");
  request_.mutable_t_w_c()->mutable_translation()->set_x(-2e5);
  refused("translation 200 km", "T_W_C.translation.x is -200000 m");
  request_.mutable_depth()->set_depth_scale(1e300);
  refused("depth_scale 1e300", "depth.depth_scale 1e+300 must lie in (0, 1]");
  request_.mutable_color()->set_encoding(static_cast<v1::Image::Encoding>(99));
  refused("encoding 99", "color.encoding 99 is not a colour encoding");
  request_.mutable_color()->set_encoding(v1::Image::RAW_DEPTH_U16);
  refused("a depth encoding for colour", "color.encoding RAW_DEPTH_U16 (");

  // Depth of 1e30 m, of 2 km and of 1.5 m in a float image: the first two are no depth.
  std::string bytes;
  for (const float depth_m : {1e30f, 2000.f, 1.5f}) {
    char raw[4];
    std::memcpy(raw, &depth_m, 4);
    bytes.append(raw, 4);
  }
  bytes.resize(8 * 6 * 4, '\0');
  *request_.mutable_depth() = MakeImage(v1::Image::RAW_DEPTH_F32, bytes, 8, 6);
  ASSERT_TRUE(Convert()) << why_;
  EXPECT_EQ(frame_.depth.depth_m[0], 0.f);
  EXPECT_EQ(frame_.depth.depth_m[1], 0.f);
  EXPECT_EQ(frame_.depth.depth_m[2], 1.5f);
}

TEST_F(FrameFromRequestTest, DepthSizeMustMatchTheIntrinsics) {
  *request_.mutable_depth() = MakeImage(v1::Image::PNG, Encode(DepthUnits(4, 3), ".png"));
  EXPECT_FALSE(Convert());
  EXPECT_EQ(why_, "depth is 4x3 but the intrinsics say 8x6");
}

}  // namespace
}  // namespace objmap::grpc_service
