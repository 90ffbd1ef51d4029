#pragma once
// Frames from an OpenNI2 device (live) or an .oni recording played back; OpenNI2 itself stays
// inside openni2_source.cc.

#include <memory>
#include <string>

#include "dataset/frame_stream.h"

namespace objmap {

/// Which OpenNI2 source to open and how its streams are set up.
struct OpenNI2SourceConfig {
  /// Device URI as OpenNI2 lists it; empty: the first device found. Exclusive with oni_path.
  std::string device_uri;
  /// An .oni recording to play back instead of a device. Exclusive with device_uri.
  std::string oni_path;
  /// Live streams: depth and colour resolution and frame rate (a recording keeps its own).
  int width = 640;
  int height = 480;
  int fps = 30;
  /// Live streams: register depth to colour when the device can, so that one set of intrinsics
  /// (the colour camera's) fits both images.
  bool depth_to_color_registration = true;
  /// Live streams: mirror the images (OpenNI2 devices often default to mirrored for gestures).
  bool mirror = false;
  /// Recording: speed as a ratio of real time (1 = as recorded); 0 = as fast as the file decodes
  /// (frames may be dropped); -1 = one frame each time one is read, none dropped (OpenNI2's
  /// PlaybackControl::setSpeed(-1)).
  double playback_speed = -1.0;
  /// How long the first frame may take after the streams start (sensors warm up), milliseconds.
  int open_timeout_ms = 5000;
  /// How long any later frame may take, milliseconds; a live camera silent that long has failed,
  /// a recording has ended.
  int read_timeout_ms = 2000;
  /// Largest depth/colour timestamp difference for a pair, seconds (half a frame at 30 Hz).
  double max_pair_dt_s = 0.017;
  /// Field of view taken when the stream reports none (some drivers and recordings), degrees;
  /// the defaults are the PrimeSense depth camera's.
  double fallback_horizontal_fov_deg = 58.0;
  double fallback_vertical_fov_deg = 45.0;

  /// False naming the field when a value is out of range or both sources are given.
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Synchronised depth (metres, 0 invalid) and colour (RGB8) pairs of one OpenNI2 device or
/// recording. Intrinsics come from the stream's field of view (fx = width / (2 tan(hfov / 2))),
/// the stamp from the depth frame (device clock, seconds), T_W_C is identity (see
/// dataset/trajectory.h for poses). Pairs come from OpenNI2's frame sync where the device has
/// it, else by nearest timestamps. Thread-safety: none.
class OpenNI2Source : public FrameStream {
 public:
  /// Initialises OpenNI2, opens the device or recording and starts both streams. Returns nullptr
  /// and a reason otherwise: "no OpenNI2 device found: ..." without a device, the path for a
  /// missing or unreadable recording. Never waits longer than the driver's device enumeration.
  [[nodiscard]] static std::unique_ptr<OpenNI2Source> Open(const OpenNI2SourceConfig& config,
                                                           std::string* why);
  ~OpenNI2Source() override;
  OpenNI2Source(const OpenNI2Source&) = delete;
  OpenNI2Source& operator=(const OpenNI2Source&) = delete;

  /// The next pair; kEnded at the end of a recording, kFailed when a live camera stops sending.
  [[nodiscard]] FrameStatus Next(RgbdFrame* frame, std::string* why) override;
  /// Frames in a recording (its depth stream), 0 for a live camera.
  [[nodiscard]] std::size_t size() const override;
  [[nodiscard]] std::string Describe() const override;
  /// Intrinsics given to every frame.
  [[nodiscard]] const CameraIntrinsics& intrinsics() const;

 private:
  struct Impl;
  explicit OpenNI2Source(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap
