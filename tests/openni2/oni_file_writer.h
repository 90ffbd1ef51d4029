#pragma once
// Writes small .oni recordings (OpenNI2's file format, version 1.0.1.0) for tests: a depth node
// (1 mm units) and a colour node (RGB888), uncompressed, with a field of view, so that OpenNI2's
// own OniFile driver plays them back as it would a camera's recording. The layout follows
// OpenNI2's Source/Core/OniDataRecords.cpp (the recorder) and Source/Drivers/OniFile (the player).
//
// openni::Recorder cannot make these here: the only device without hardware, DummyDevice, reports
// no cropping property, and the player drops every frame of a node recorded without one.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "types/frame.h"

namespace objmap::testing {

struct OniTestFrame {
  std::uint64_t timestamp_us = 0;
  std::vector<std::uint16_t> depth_mm;  ///< width * height
  std::vector<std::uint8_t> rgb;        ///< width * height * 3
};

struct OniTestRecording {
  int width = 64;
  int height = 48;
  int fps = 30;
  float horizontal_fov_rad = 1.0f;
  float vertical_fov_rad = 0.8f;
  std::vector<OniTestFrame> frames;  ///< both nodes get one frame each, at the same stamp
};

namespace oni_detail {

enum : std::uint32_t {
  kIntProperty = 0x03,
  kGeneralProperty = 0x06,
  kNodeDataBegin = 0x08,
  kNodeStateReady = 0x09,
  kNewData = 0x0A,
  kEnd = 0x0B,
  kNodeAdded = 0x0D,
};
enum : std::uint32_t { kNodeDepth = 2, kNodeImage = 3 };
constexpr std::uint32_t kCodecUncompressed = 'N' | 'O' << 8 | 'N' << 16 | 'E' << 24;

// One record: a 28-byte header (magic "NIR\0", type, node, fields size including the header,
// payload size, undo position), the fields, then the payload.
class RecordBuilder {
 public:
  RecordBuilder(std::uint32_t type, std::uint32_t node) : type_(type), node_(node) {}
  template <typename T>
  RecordBuilder& Add(const T& value) {
    const auto* bytes = reinterpret_cast<const char*>(&value);
    fields_.insert(fields_.end(), bytes, bytes + sizeof(T));
    return *this;
  }
  RecordBuilder& AddString(const std::string& text) {
    Add(static_cast<std::uint32_t>(text.size() + 1));
    fields_.insert(fields_.end(), text.c_str(), text.c_str() + text.size() + 1);
    return *this;
  }
  RecordBuilder& AddBytes(const void* data, std::size_t size) {
    const auto* bytes = static_cast<const char*>(data);
    fields_.insert(fields_.end(), bytes, bytes + size);
    return *this;
  }
  void WriteTo(std::ofstream& out, const void* payload = nullptr, std::uint32_t payload_size = 0) {
    const std::uint32_t header[5] = {0x0052494E, type_, node_,
                                     static_cast<std::uint32_t>(28 + fields_.size()), payload_size};
    const std::uint64_t undo_position = 0;
    out.write(reinterpret_cast<const char*>(header), sizeof(header));
    out.write(reinterpret_cast<const char*>(&undo_position), sizeof(undo_position));
    out.write(fields_.data(), static_cast<std::streamsize>(fields_.size()));
    if (payload_size > 0) out.write(static_cast<const char*>(payload), payload_size);
  }

 private:
  std::uint32_t type_, node_;
  std::vector<char> fields_;
};

inline void WriteProperty(std::ofstream& out, std::uint32_t node, const std::string& name,
                          const void* data, std::uint32_t size) {
  RecordBuilder(kGeneralProperty, node).AddString(name).Add(size).AddBytes(data, size).WriteTo(out);
}

inline void WriteIntProperty(std::ofstream& out, std::uint32_t node, const std::string& name,
                             std::uint64_t value) {
  RecordBuilder(kIntProperty, node)
      .AddString(name)
      .Add(static_cast<std::uint32_t>(sizeof(value)))
      .Add(value)
      .WriteTo(out);
}

// NodeAdded and the properties the player needs before it delivers a node's frames. Every node
// must be declared before the first NodeDataBegin: opening a file stops reading there.
inline void WriteNode(std::ofstream& out, std::uint32_t node, bool is_depth,
                      const OniTestRecording& recording) {
  const auto frames = static_cast<std::uint32_t>(recording.frames.size());
  const std::uint64_t last_stamp = frames > 0 ? recording.frames.back().timestamp_us : 0;
  const std::uint32_t pixel_bytes = is_depth ? 2 : 3;
  RecordBuilder(kNodeAdded, node)
      .AddString(is_depth ? "Depth" : "Image")
      .Add(is_depth ? std::uint32_t{kNodeDepth} : std::uint32_t{kNodeImage})
      .Add(kCodecUncompressed)
      .Add(frames)
      .Add(std::uint64_t{0})
      .Add(last_stamp)
      .Add(std::uint64_t{0})  // no seek table
      .WriteTo(out);
  WriteIntProperty(out, node, "oniRequiredFrameSize",
                   std::uint64_t{pixel_bytes} * recording.width * recording.height);
  WriteIntProperty(out, node, "xnIsGenerating", 1);
  const std::uint32_t mode[3] = {static_cast<std::uint32_t>(recording.width),
                                 static_cast<std::uint32_t>(recording.height),
                                 static_cast<std::uint32_t>(recording.fps)};
  WriteProperty(out, node, "xnMapOutputMode", mode, sizeof(mode));
  WriteIntProperty(out, node, "xnPixelFormat", is_depth ? 4 : 1);       // grey 16 bit, RGB24
  WriteIntProperty(out, node, "oniPixelFormat", is_depth ? 100 : 200);  // DEPTH_1_MM, RGB888
  const double fov[2] = {recording.horizontal_fov_rad, recording.vertical_fov_rad};
  WriteProperty(out, node, "xnFOV", fov, sizeof(fov));
  struct {
    std::int32_t enabled = 0;
    std::uint16_t x = 0, y = 0, width = 0, height = 0;
  } cropping;
  static_assert(sizeof(cropping) == 12, "XnCropping is 12 bytes");
  WriteProperty(out, node, "xnCropping", &cropping, sizeof(cropping));
}

}  // namespace oni_detail

/// `frames` (same size and intrinsics, depth in metres) as a camera would record them: the field
/// of view of their focal lengths, 1 mm depth units, `frame_interval_us` apart (the first one
/// interval after 0).
inline OniTestRecording RecordingOf(const std::vector<RgbdFrame>& frames,
                                    std::uint64_t frame_interval_us) {
  OniTestRecording recording;
  if (frames.empty()) return recording;
  const CameraIntrinsics& K = frames.front().intrinsics;
  recording.width = K.width;
  recording.height = K.height;
  recording.horizontal_fov_rad = static_cast<float>(2.0 * std::atan(0.5 * K.width / K.fx));
  recording.vertical_fov_rad = static_cast<float>(2.0 * std::atan(0.5 * K.height / K.fy));
  for (std::size_t n = 0; n < frames.size(); ++n) {
    OniTestFrame oni;
    oni.timestamp_us = frame_interval_us * (n + 1);
    oni.rgb = frames[n].color.rgb;
    oni.depth_mm.reserve(frames[n].depth.depth_m.size());
    for (const float z : frames[n].depth.depth_m) {
      oni.depth_mm.push_back(z > 0.f ? static_cast<std::uint16_t>(std::lround(z * 1000.f)) : 0);
    }
    recording.frames.push_back(std::move(oni));
  }
  return recording;
}

/// `count` frames 1/30 s apart (the first at 1/30 s) of a camera facing a flat wall
/// `depth_mm` away, every colour pixel grey `gray`.
inline OniTestRecording WallRecording(int count, int width, int height, std::uint16_t depth_mm,
                                      std::uint8_t gray) {
  OniTestRecording recording;
  recording.width = width;
  recording.height = height;
  for (int i = 0; i < count; ++i) {
    OniTestFrame frame;
    frame.timestamp_us = 33333u * static_cast<std::uint64_t>(i + 1);
    frame.depth_mm.assign(static_cast<std::size_t>(width) * height, depth_mm);
    frame.rgb.assign(static_cast<std::size_t>(width) * height * 3, gray);
    recording.frames.push_back(frame);
  }
  return recording;
}

/// Writes `recording` to `path`; false when the file cannot be written.
inline bool WriteOniFile(const std::string& path, const OniTestRecording& recording) {
  using namespace oni_detail;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  const char identity[4] = {'N', 'I', '1', '0'};
  const std::uint8_t version_major_minor[2] = {1, 0};
  const std::uint16_t maintenance = 1;
  const std::uint32_t build = 0;
  const std::uint64_t max_timestamp = UINT64_MAX;
  const std::uint32_t max_node_id = 2;
  out.write(identity, 4);
  out.write(reinterpret_cast<const char*>(version_major_minor), 2);
  out.write(reinterpret_cast<const char*>(&maintenance), 2);
  out.write(reinterpret_cast<const char*>(&build), 4);
  out.write(reinterpret_cast<const char*>(&max_timestamp), 8);
  out.write(reinterpret_cast<const char*>(&max_node_id), 4);
  WriteNode(out, 1, true, recording);
  WriteNode(out, 2, false, recording);
  const auto frames = static_cast<std::uint32_t>(recording.frames.size());
  const std::uint64_t last_stamp = frames > 0 ? recording.frames.back().timestamp_us : 0;
  for (std::uint32_t node = 1; node <= 2; ++node) {
    RecordBuilder(kNodeStateReady, node).WriteTo(out);
    RecordBuilder(kNodeDataBegin, node).Add(frames).Add(last_stamp).WriteTo(out);
  }
  std::uint32_t frame_id = 1;  // frame ids start at 1
  for (const OniTestFrame& frame : recording.frames) {
    RecordBuilder(kNewData, 1)
        .Add(frame.timestamp_us)
        .Add(frame_id)
        .WriteTo(out, frame.depth_mm.data(), static_cast<std::uint32_t>(frame.depth_mm.size() * 2));
    RecordBuilder(kNewData, 2)
        .Add(frame.timestamp_us)
        .Add(frame_id)
        .WriteTo(out, frame.rgb.data(), static_cast<std::uint32_t>(frame.rgb.size()));
    ++frame_id;
  }
  RecordBuilder(kEnd, 0).WriteTo(out);
  return static_cast<bool>(out);
}

}  // namespace objmap::testing
