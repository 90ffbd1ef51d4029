// What the ROS inputs cost per 640x480 frame before mapping starts, each against a plain
// baseline in the same run:
//   ros_input_bench [sequence=../shared/data/redkitchen] [frames=100] [repeats=20]
// - the node's side of a frame: the ROS deserialization of colour, depth and camera info (what
//   TCPROS hands a subscriber) plus ros_bridge::FrameFromMsgs (checks, rgb8 copy, 16UC1 to
//   metres, ValidateFrame), against memcpy of the same bytes;
// - `objmap map FILE.bag`: OpenRosbagSequence's index of a bag written from `frames` frames
//   and ReadFrame of each, against ReadFrame of the same frames from the folder (JPEG + PNG
//   decoding).
#include <ros/serialization.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_timing.h"
#include "dataset/sequence_reader.h"
#include "ros_conversions.h"
#include "rosbag_input.h"
#include "rosbag_input/test_bags.h"

namespace {

using objmap::bench::Clock;
using objmap::bench::Ms;
using objmap::bench::Median;

template <typename Message>
std::vector<std::uint8_t> Serialize(const Message& message) {
  std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(message));
  ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::serialize(stream, message);
  return bytes;
}

template <typename Message>
Message Deserialize(std::vector<std::uint8_t>& bytes) {
  Message message;
  ros::serialization::IStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ros::serialization::deserialize(stream, message);
  return message;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string sequence = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const std::size_t frames = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 100;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 20;
  std::string why;
  auto reader = objmap::OpenSequence(sequence, &why);
  if (!reader) {
    std::fprintf(stderr, "ros_input_bench: %s\n", why.c_str());
    return 1;
  }
  std::vector<objmap::RgbdFrame> read(std::min(frames, reader->size()));
  for (std::size_t i = 0; i < read.size(); ++i) {
    if (!reader->ReadFrame(i, &read[i], &why)) {
      std::fprintf(stderr, "ros_input_bench: %s\n", why.c_str());
      return 1;
    }
  }

  // The node's side of one frame, on frame 0's messages as they arrive over TCPROS.
  sensor_msgs::Image color_msg = objmap::ros_bridge::ColorToMsg(read[0].color);
  sensor_msgs::Image depth_msg = objmap::ros_bridge::DepthToMsgMillimetres(read[0].depth);
  sensor_msgs::CameraInfo info_msg = objmap::ros_bridge::IntrinsicsToMsg(read[0].intrinsics);
  std::vector<std::uint8_t> color_bytes = Serialize(color_msg);
  std::vector<std::uint8_t> depth_bytes = Serialize(depth_msg);
  std::vector<std::uint8_t> info_bytes = Serialize(info_msg);
  std::vector<double> node_ms, copy_ms;
  std::vector<std::uint8_t> sink(color_bytes.size() + depth_bytes.size());
  for (int r = 0; r < repeats * 10; ++r) {
    auto start = Clock::now();
    const auto color = Deserialize<sensor_msgs::Image>(color_bytes);
    const auto depth = Deserialize<sensor_msgs::Image>(depth_bytes);
    const auto info = Deserialize<sensor_msgs::CameraInfo>(info_bytes);
    objmap::RgbdFrame frame;
    if (!objmap::ros_bridge::FrameFromMsgs(color, depth, info, read[0].T_W_C, 0.001, &frame,
                                           &why)) {
      std::fprintf(stderr, "ros_input_bench: %s\n", why.c_str());
      return 1;
    }
    node_ms.push_back(Ms(start));
    start = Clock::now();
    std::memcpy(sink.data(), color_bytes.data(), color_bytes.size());
    std::memcpy(sink.data() + color_bytes.size(), depth_bytes.data(), depth_bytes.size());
    copy_ms.push_back(Ms(start));
  }
  std::printf("node input, one %dx%d frame (%zu message bytes), median of %d:\n",
              read[0].color.width, read[0].color.height,
              color_bytes.size() + depth_bytes.size() + info_bytes.size(), repeats * 10);
  std::printf("  deserialize + FrameFromMsgs   %7.3f ms\n", Median(node_ms));
  std::printf("  memcpy of the image bytes     %7.3f ms   (ratio %.1fx)\n", Median(copy_ms),
              Median(node_ms) / std::max(Median(copy_ms), 1e-6));

  // A bag of the frames against the folder they came from.
  const std::string bag = (std::filesystem::temp_directory_path() /
                           ("objmap_ros_input_bench_" + std::to_string(::getpid()) + ".bag"))
                              .string();
  objmap::testing::WriteTestBag(bag, read);
  const double bag_mb = static_cast<double>(std::filesystem::file_size(bag)) / 1e6;
  std::vector<double> index_ms, bag_frame_ms, folder_frame_ms;
  for (int r = 0; r < std::max(1, repeats / 10); ++r) {
    auto start = Clock::now();
    auto bag_reader = objmap::OpenRosbagSequence(bag, objmap::RosbagInputConfig(), &why);
    if (!bag_reader) {
      std::fprintf(stderr, "ros_input_bench: %s\n", why.c_str());
      return 1;
    }
    index_ms.push_back(Ms(start));
    for (std::size_t i = 0; i < read.size(); ++i) {
      objmap::RgbdFrame frame;
      start = Clock::now();
      if (!bag_reader->ReadFrame(i, &frame, &why)) {
        std::fprintf(stderr, "ros_input_bench: %s\n", why.c_str());
        return 1;
      }
      bag_frame_ms.push_back(Ms(start));
      start = Clock::now();
      if (!reader->ReadFrame(i, &frame, &why)) return 1;
      folder_frame_ms.push_back(Ms(start));
    }
  }
  std::filesystem::remove(bag);
  std::printf("bag of %zu frames (%.0f MB, raw rgb8 + 16UC1):\n", read.size(), bag_mb);
  std::printf("  OpenRosbagSequence (index)    %7.1f ms  (%.2f ms per frame)\n", Median(index_ms),
              Median(index_ms) / static_cast<double>(read.size()));
  std::printf("  ReadFrame from the bag        %7.3f ms\n", Median(bag_frame_ms));
  std::printf("  ReadFrame from the folder     %7.3f ms   (JPEG + PNG; bag is %.1fx faster)\n",
              Median(folder_frame_ms), Median(folder_frame_ms) / Median(bag_frame_ms));
  return 0;
}
