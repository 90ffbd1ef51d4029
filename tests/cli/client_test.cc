// The client library without a server: frame encoding, geometry conversions, status names, and
// how calls fail against a port where nothing (or something that is not gRPC) listens.
#include "objmap/client.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>

#include "objmap/conversions.h"
#include "objmap/keyframe_request.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// A frame with a colour gradient and a depth ramp that has invalid pixels of every kind.
RgbdFrame TestFrame() {
  RgbdFrame frame;
  frame.name = "frame-000042";
  frame.stamp_s = 12.5;
  frame.intrinsics = {64, 48, 50.0, 51.0, 31.5, 23.5};
  frame.color = {64, 48, std::vector<std::uint8_t>(64 * 48 * 3)};
  frame.depth = {64, 48, std::vector<float>(64 * 48)};
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {
      const std::size_t k = static_cast<std::size_t>(v) * 64 + u;
      frame.color.rgb[3 * k] = static_cast<std::uint8_t>(4 * u);
      frame.color.rgb[3 * k + 1] = static_cast<std::uint8_t>(5 * v);
      frame.color.rgb[3 * k + 2] = static_cast<std::uint8_t>(200 - u - v);
      frame.depth.depth_m[k] = 0.5f + 0.001f * static_cast<float>(k);
    }
  }
  frame.depth.depth_m[0] = 0.f;
  frame.depth.depth_m[1] = std::nanf("");
  frame.depth.depth_m[2] = -1.f;
  frame.depth.depth_m[3] = 70.f;  // beyond 65.535 m
  frame.T_W_C = Eigen::Translation3d(1.0, -2.0, 0.5) *
                Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized());
  return frame;
}

TEST(KeyframeRequest, PngRoundTripIsExactToTheMillimetre) {
  const RgbdFrame frame = TestFrame();
  v1::AddKeyframeRequest request;
  std::string why;
  ASSERT_TRUE(MakeAddKeyframeRequest(frame, nullptr, {}, &request, &why)) << why;
  EXPECT_EQ(request.color().encoding(), v1::Image::PNG);
  EXPECT_EQ(request.depth().encoding(), v1::Image::PNG);
  EXPECT_DOUBLE_EQ(request.depth().depth_scale(), 0.001);
  EXPECT_EQ(request.name(), "frame-000042");
  EXPECT_FALSE(request.detections_given());
  EXPECT_EQ(request.intrinsics().fy(), 51.0);

  RgbdFrame decoded;
  ASSERT_TRUE(DecodeAddKeyframeRequest(request, &decoded, &why)) << why;
  EXPECT_EQ(decoded.color.rgb, frame.color.rgb);
  ASSERT_EQ(decoded.depth.depth_m.size(), frame.depth.depth_m.size());
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(decoded.depth.depth_m[k], 0.f) << k;
  for (std::size_t k = 4; k < frame.depth.depth_m.size(); ++k) {
    ASSERT_NEAR(decoded.depth.depth_m[k], frame.depth.depth_m[k], 0.0005 + 1e-6) << k;
  }
  EXPECT_TRUE(decoded.T_W_C.isApprox(frame.T_W_C, 1e-12));
  EXPECT_EQ(decoded.stamp_s, 12.5);
  EXPECT_EQ(decoded.intrinsics.cx, 31.5);
}

TEST(KeyframeRequest, JpegIsSmallerAndClose) {
  const RgbdFrame frame = TestFrame();
  v1::AddKeyframeRequest png;
  v1::AddKeyframeRequest jpeg;
  KeyframeEncoding encoding;
  std::string why;
  ASSERT_TRUE(MakeAddKeyframeRequest(frame, nullptr, encoding, &png, &why)) << why;
  encoding.color = KeyframeEncoding::Color::kJpeg;
  encoding.jpeg_quality = 90;
  ASSERT_TRUE(MakeAddKeyframeRequest(frame, nullptr, encoding, &jpeg, &why)) << why;
  EXPECT_EQ(jpeg.color().encoding(), v1::Image::JPEG);
  EXPECT_LT(jpeg.color().data().size(), png.color().data().size());
  RgbdFrame decoded;
  ASSERT_TRUE(DecodeAddKeyframeRequest(jpeg, &decoded, &why)) << why;
  double error_sum = 0.0;
  for (std::size_t i = 0; i < frame.color.rgb.size(); ++i) {
    error_sum += std::abs(static_cast<int>(decoded.color.rgb[i]) - frame.color.rgb[i]);
  }
  EXPECT_LT(error_sum / static_cast<double>(frame.color.rgb.size()), 4.0);
}

TEST(KeyframeRequest, DetectionsAreSentWithClassNames) {
  const RgbdFrame frame = TestFrame();
  const int cup = CocoClassId("cup");
  const std::vector<Detection> detections = {{{1.f, 2.f, 30.f, 40.f}, cup, 0.75f}};
  v1::AddKeyframeRequest request;
  std::string why;
  ASSERT_TRUE(MakeAddKeyframeRequest(frame, &detections, {}, &request, &why)) << why;
  EXPECT_TRUE(request.detections_given());
  ASSERT_EQ(request.detections_size(), 1);
  EXPECT_EQ(request.detections(0).class_name(), "cup");
  EXPECT_EQ(request.detections(0).class_id(), cup);
  EXPECT_EQ(request.detections(0).x_max(), 30.f);
  EXPECT_FLOAT_EQ(request.detections(0).score(), 0.75f);

  // An empty list still means "these are the detections: none", not "detect for me".
  const std::vector<Detection> none;
  v1::AddKeyframeRequest empty;
  ASSERT_TRUE(MakeAddKeyframeRequest(frame, &none, {}, &empty, &why)) << why;
  EXPECT_TRUE(empty.detections_given());
  EXPECT_EQ(empty.detections_size(), 0);
}

TEST(KeyframeRequest, BadFramesAndOptionsAreNamed) {
  RgbdFrame frame = TestFrame();
  frame.depth.depth_m.pop_back();
  v1::AddKeyframeRequest request;
  std::string why;
  EXPECT_FALSE(MakeAddKeyframeRequest(frame, nullptr, {}, &request, &why));
  EXPECT_EQ(why.rfind("frame-000042: depth image", 0), 0u) << why;

  frame = TestFrame();
  KeyframeEncoding encoding;
  encoding.jpeg_quality = 0;
  EXPECT_FALSE(MakeAddKeyframeRequest(frame, nullptr, encoding, &request, &why));
  EXPECT_NE(why.find("jpeg_quality"), std::string::npos) << why;
}

TEST(Conversions, PoseRoundTripAndValidation) {
  const Eigen::Isometry3d T = TestFrame().T_W_C;
  const v1::Pose pose = PoseToProto(T);
  EXPECT_NEAR(std::hypot(std::hypot(pose.qx(), pose.qy()), std::hypot(pose.qz(), pose.qw())), 1.0,
              1e-12);
  Eigen::Isometry3d back;
  std::string why;
  ASSERT_TRUE(PoseFromProto(pose, &back, &why)) << why;
  EXPECT_TRUE(back.isApprox(T, 1e-12));

  v1::Pose scaled = pose;  // a non-unit quaternion is normalized
  scaled.set_qx(2 * pose.qx());
  scaled.set_qy(2 * pose.qy());
  scaled.set_qz(2 * pose.qz());
  scaled.set_qw(2 * pose.qw());
  ASSERT_TRUE(PoseFromProto(scaled, &back, &why)) << why;
  EXPECT_TRUE(back.isApprox(T, 1e-12));

  v1::Pose zero;
  EXPECT_FALSE(PoseFromProto(zero, &back, &why));
  EXPECT_EQ(why, "pose quaternion is zero");
  v1::Pose nan = pose;
  nan.mutable_translation()->set_y(std::nan(""));
  EXPECT_FALSE(PoseFromProto(nan, &back, &why));
  EXPECT_EQ(why, "pose has NaN or infinite entries");

  const v1::Box box = BoxToProto({-1, -2, -3}, {1, 2, 3});
  EXPECT_EQ(Vec3FromProto(box.min()), Eigen::Vector3d(-1, -2, -3));
  EXPECT_EQ(Vec3FromProto(box.max()), Eigen::Vector3d(1, 2, 3));
}

TEST(Conversions, ObjectModelRoundTripAndSizeCheck) {
  const std::vector<Eigen::Vector3f> points = {{0.1f, -0.2f, 0.3f}, {1e-3f, 2.5f, -7.f}};
  const std::vector<std::array<std::uint8_t, 3>> colors = {{{1, 2, 3}}, {{250, 128, 0}}};
  v1::Object object;
  object.set_id(17);
  EncodeObjectModel(points, colors, &object);
  EXPECT_EQ(object.num_points(), 2);
  EXPECT_EQ(object.points_xyz().size(), 24u);
  // Little-endian float32 on the wire: 0.1f is 0x3dcccccd.
  EXPECT_EQ(static_cast<unsigned char>(object.points_xyz()[0]), 0xcd);
  EXPECT_EQ(static_cast<unsigned char>(object.points_xyz()[3]), 0x3d);
  std::vector<Eigen::Vector3f> points_back;
  std::vector<std::array<std::uint8_t, 3>> colors_back;
  std::string why;
  ASSERT_TRUE(DecodeObjectModel(object, &points_back, &colors_back, &why)) << why;
  EXPECT_EQ(points_back, points);
  EXPECT_EQ(colors_back, colors);

  object.mutable_points_rgb()->pop_back();
  EXPECT_FALSE(DecodeObjectModel(object, &points_back, &colors_back, &why));
  EXPECT_EQ(why, "object 17: model has 2 points but 24 xyz bytes and 5 rgb bytes");
}

TEST(StatusNames, CodesAndMessages) {
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::INVALID_ARGUMENT), "INVALID_ARGUMENT");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::NOT_FOUND), "NOT_FOUND");
  EXPECT_EQ(StatusCodeName(grpc::StatusCode::RESOURCE_EXHAUSTED), "RESOURCE_EXHAUSTED");
  EXPECT_EQ(DescribeStatus(grpc::Status(grpc::StatusCode::NOT_FOUND, "id: no object 9")),
            "NOT_FOUND: id: no object 9");
  EXPECT_EQ(DescribeStatus(grpc::Status::OK), "OK");
}

// A loopback socket bound to a free port. listen() makes it accept TCP connections that are
// never answered (not a gRPC server); without it nothing accepts.
class LoopbackSocket {
 public:
  explicit LoopbackSocket(bool listen) : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof(address);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&address), length) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
      return;
    }
    port_ = ntohs(address.sin_port);
    if (listen) ::listen(fd_, 4);
  }
  ~LoopbackSocket() { ::close(fd_); }
  std::string Address() const { return "127.0.0.1:" + std::to_string(port_); }
  int port() const { return port_; }

 private:
  int fd_;
  int port_ = 0;
};

TEST(MapClient, NoServerIsUnavailable) {
  const LoopbackSocket closed(false);  // bound, not listening: connections are refused
  ASSERT_GT(closed.port(), 0);
  MapClient client(closed.Address());
  EXPECT_FALSE(client.WaitForServer(std::chrono::milliseconds(200)));
  v1::StatusResponse response;
  const grpc::Status status = client.Status(v1::StatusRequest(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << DescribeStatus(status);

  std::unique_ptr<IngestWriter> writer = client.StartIngest();
  grpc::Status write = writer->Write(TestFrame(), nullptr);
  v1::IngestSummary summary;
  const grpc::Status finish = writer->Finish(&summary);
  EXPECT_EQ(finish.error_code(), grpc::StatusCode::UNAVAILABLE) << DescribeStatus(finish);
  if (!write.ok()) {
    EXPECT_EQ(write.error_code(), grpc::StatusCode::UNAVAILABLE);
  }
  // Writing after the end answers the final status again.
  EXPECT_EQ(writer->Write(TestFrame(), nullptr).error_code(), grpc::StatusCode::UNAVAILABLE);
}

TEST(MapClient, DeadlineAppliesToEveryCall) {
  const LoopbackSocket silent(true);  // accepts TCP, never speaks HTTP/2
  ASSERT_GT(silent.port(), 0);
  MapClientOptions options;
  options.deadline_s = 0.3;
  MapClient client(silent.Address(), options);
  const auto start = std::chrono::steady_clock::now();
  v1::InventoryResponse response;
  const grpc::Status status = client.Inventory(v1::InventoryRequest(), &response);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << DescribeStatus(status);
  EXPECT_LT(elapsed_s, 5.0);
}

TEST(MapClient, InvalidOptionsAnswerInvalidArgument) {
  MapClientOptions options;
  options.deadline_s = -1.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  MapClient client("127.0.0.1:1", options);
  v1::StatusResponse response;
  grpc::Status status = client.Status(v1::StatusRequest(), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "MapClientOptions: deadline_s must be finite and >= 0");
  v1::AddKeyframeResponse added;
  status = client.AddKeyframe(TestFrame(), nullptr, &added);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::IngestSummary summary;
  EXPECT_EQ(client.StartIngest()->Finish(&summary).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

}  // namespace
}  // namespace objmap
