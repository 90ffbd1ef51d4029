#include "openni2/openni2_source.h"

#include <OpenNI.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <thread>

namespace objmap {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Some drivers (OpenNI2's DummyDevice among them) stop a stream by clearing a flag that their
// frame thread polls once per frame, without joining the thread; destroying the stream or
// unloading the driver before the thread has seen the flag crashes. Two frame periods suffice.
constexpr auto kDriverStopGrace = std::chrono::milliseconds(100);

// OpenNI::getExtendedError() without its leading tab and trailing newline.
std::string ExtendedError() {
  std::string text = openni::OpenNI::getExtendedError();
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "no details from OpenNI2";
  return text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
}

// Focal length of a pinhole camera `pixels` wide across a field of view of `fov_rad`.
double FocalLength(int pixels, double fov_rad) { return pixels / (2.0 * std::tan(fov_rad / 2.0)); }

bool IsUsableFov(float fov_rad) {
  return std::isfinite(fov_rad) && fov_rad > 0.01f && fov_rad < 3.1f;
}

std::string ModeText(const openni::VideoMode& mode) {
  return std::to_string(mode.getResolutionX()) + "x" + std::to_string(mode.getResolutionY()) + "@" +
         std::to_string(mode.getFps());
}

// Selects width x height @ fps in `format` among the sensor's modes; false listing the modes.
bool SetVideoMode(openni::VideoStream* stream, openni::PixelFormat format, const char* what,
                  const OpenNI2SourceConfig& config, std::string* why) {
  const auto wanted = [&](const openni::VideoMode& mode) {
    return mode.getPixelFormat() == format && mode.getResolutionX() == config.width &&
           mode.getResolutionY() == config.height && mode.getFps() == config.fps;
  };
  // Already in that mode: nothing to set (some drivers cannot set a mode at all).
  if (wanted(stream->getVideoMode())) return true;
  const auto& modes = stream->getSensorInfo().getSupportedVideoModes();
  std::string offered;
  for (int i = 0; i < modes.getSize(); ++i) {
    const openni::VideoMode& mode = modes[i];
    if (wanted(mode)) {
      if (stream->setVideoMode(mode) == openni::STATUS_OK) return true;
      *why = std::string(what) + " mode " + ModeText(mode) + " refused: " + ExtendedError();
      return false;
    }
    if (mode.getPixelFormat() == format) offered += (offered.empty() ? "" : ", ") + ModeText(mode);
  }
  *why = std::string("the ") + what + " stream has no " + std::to_string(config.width) + "x" +
         std::to_string(config.height) + "@" + std::to_string(config.fps) +
         " mode (it has: " + (offered.empty() ? "none in the needed pixel format" : offered) + ")";
  return false;
}

// Depth in metres from a DEPTH_1_MM or DEPTH_100_UM frame; false for another pixel format.
bool ConvertDepth(const openni::VideoFrameRef& frame, DepthImage* image) {
  const openni::PixelFormat format = frame.getVideoMode().getPixelFormat();
  float metres_per_unit = 0.0f;
  if (format == openni::PIXEL_FORMAT_DEPTH_1_MM) metres_per_unit = 0.001f;
  if (format == openni::PIXEL_FORMAT_DEPTH_100_UM) metres_per_unit = 0.0001f;
  if (metres_per_unit == 0.0f) return false;
  image->width = frame.getWidth();
  image->height = frame.getHeight();
  image->depth_m.resize(static_cast<std::size_t>(image->width) * image->height);
  const auto* bytes = static_cast<const std::uint8_t*>(frame.getData());
  for (int v = 0; v < image->height; ++v) {
    const auto* row =
        reinterpret_cast<const openni::DepthPixel*>(bytes + v * frame.getStrideInBytes());
    float* out = image->depth_m.data() + static_cast<std::size_t>(v) * image->width;
    for (int u = 0; u < image->width; ++u) out[u] = row[u] * metres_per_unit;  // 0 stays invalid
  }
  return true;
}

// RGB8 from an RGB888 frame; false for another pixel format.
bool ConvertColor(const openni::VideoFrameRef& frame, ColorImage* image) {
  if (frame.getVideoMode().getPixelFormat() != openni::PIXEL_FORMAT_RGB888) return false;
  image->width = frame.getWidth();
  image->height = frame.getHeight();
  const std::size_t row_bytes = static_cast<std::size_t>(image->width) * 3;
  image->rgb.resize(row_bytes * image->height);
  const auto* bytes = static_cast<const std::uint8_t*>(frame.getData());
  for (int v = 0; v < image->height; ++v) {
    std::copy_n(bytes + v * frame.getStrideInBytes(), row_bytes, image->rgb.data() + v * row_bytes);
  }
  return true;
}

}  // namespace

bool OpenNI2SourceConfig::IsValid(std::string* why) const {
  const auto fail = [why](const std::string& reason) {
    *why = "openni2: " + reason;
    return false;
  };
  if (!device_uri.empty() && !oni_path.empty()) {
    return fail("device_uri and oni_path are exclusive: give one source");
  }
  if (width <= 0 || height <= 0 || fps <= 0) return fail("width, height and fps must be positive");
  if (!(playback_speed == -1.0 || playback_speed >= 0.0) || !std::isfinite(playback_speed)) {
    return fail("playback_speed must be -1, 0 or positive");
  }
  if (open_timeout_ms <= 0 || read_timeout_ms <= 0) return fail("timeouts must be positive");
  if (!(max_pair_dt_s >= 0.0) || !std::isfinite(max_pair_dt_s)) {
    return fail("max_pair_dt_s must be finite and >= 0");
  }
  if (!(fallback_horizontal_fov_deg > 0.0 && fallback_horizontal_fov_deg < 180.0) ||
      !(fallback_vertical_fov_deg > 0.0 && fallback_vertical_fov_deg < 180.0)) {
    return fail("fallback fields of view must lie in (0, 180) degrees");
  }
  return true;
}

struct OpenNI2Source::Impl {
  OpenNI2SourceConfig config;
  bool initialized = false;
  openni::Device device;
  openni::VideoStream depth;
  openni::VideoStream color;
  bool started = false;
  CameraIntrinsics intrinsics;
  std::string description;
  std::string frame_prefix;  // "openni2" or the recording's file name
  int depth_frames_in_file = 0;
  int color_frames_in_file = 0;
  int depth_frames_read = 0;
  int color_frames_read = 0;
  bool first_frame = true;
  std::int64_t next_index = 0;
  openni::VideoFrameRef pending_depth;
  openni::VideoFrameRef pending_color;

  ~Impl() { Close(); }

  bool OpenDevice(std::string* why);
  bool CreateStreams(std::string* why);
  bool SetUpLiveStreams(std::string* why);
  void ComputeIntrinsics();
  bool Start(std::string* why);
  FrameStatus ReadOne(std::string* why);
  FrameStatus MakeFrame(RgbdFrame* frame, std::string* why);
  void Close();
  [[nodiscard]] bool IsFile() const { return !config.oni_path.empty(); }
};

bool OpenNI2Source::Impl::OpenDevice(std::string* why) {
  if (IsFile()) {
    if (!std::filesystem::is_regular_file(config.oni_path)) {
      *why = config.oni_path + ": no such .oni file";
      return false;
    }
  }
  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    *why = "OpenNI2 initialisation failed: " + ExtendedError();
    return false;
  }
  initialized = true;
  if (IsFile()) {
    if (device.open(config.oni_path.c_str()) != openni::STATUS_OK) {
      *why = config.oni_path + ": not a readable .oni recording (" + ExtendedError() + ")";
      return false;
    }
    frame_prefix = std::filesystem::path(config.oni_path).filename().string();
    description = "OpenNI2 recording " + config.oni_path;
    openni::PlaybackControl* playback = device.getPlaybackControl();
    playback->setRepeatEnabled(false);
    playback->setSpeed(static_cast<float>(config.playback_speed));
    return true;
  }
  const char* uri = config.device_uri.empty() ? openni::ANY_DEVICE : config.device_uri.c_str();
  if (device.open(uri) != openni::STATUS_OK) {
    *why = config.device_uri.empty()
               ? "no OpenNI2 device found: " + ExtendedError()
               : "OpenNI2 device '" + config.device_uri + "' cannot be opened: " + ExtendedError();
    return false;
  }
  frame_prefix = "openni2";
  const std::string name = device.getDeviceInfo().getName();
  description = "OpenNI2 device " + (name.empty() ? std::string() : name + " ") + "(" +
                device.getDeviceInfo().getUri() + ")";
  return true;
}

bool OpenNI2Source::Impl::CreateStreams(std::string* why) {
  const std::string where = IsFile() ? config.oni_path + ": " : description + ": ";
  if (!device.hasSensor(openni::SENSOR_DEPTH) || !device.hasSensor(openni::SENSOR_COLOR)) {
    *why = where + "needs both a depth and a colour stream";
    return false;
  }
  if (depth.create(device, openni::SENSOR_DEPTH) != openni::STATUS_OK ||
      color.create(device, openni::SENSOR_COLOR) != openni::STATUS_OK) {
    *why = where + "cannot create the streams: " + ExtendedError();
    return false;
  }
  if (IsFile()) {
    depth_frames_in_file = device.getPlaybackControl()->getNumberOfFrames(depth);
    color_frames_in_file = device.getPlaybackControl()->getNumberOfFrames(color);
    return true;
  }
  return SetUpLiveStreams(why);
}

bool OpenNI2Source::Impl::SetUpLiveStreams(std::string* why) {
  if (!SetVideoMode(&depth, openni::PIXEL_FORMAT_DEPTH_1_MM, "depth", config, why) ||
      !SetVideoMode(&color, openni::PIXEL_FORMAT_RGB888, "colour", config, why)) {
    *why = description + ": " + *why;
    return false;
  }
  // Not every driver can mirror; that only matters when mirroring is asked for.
  const bool mirrored = depth.setMirroringEnabled(config.mirror) == openni::STATUS_OK &&
                        color.setMirroringEnabled(config.mirror) == openni::STATUS_OK;
  if (config.mirror && !mirrored) {
    *why = description + ": cannot mirror the streams: " + ExtendedError();
    return false;
  }
  if (config.depth_to_color_registration &&
      device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
      device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) !=
          openni::STATUS_OK) {
    *why = description + ": depth-to-colour registration failed: " + ExtendedError();
    return false;
  }
  return true;
}

void OpenNI2Source::Impl::ComputeIntrinsics() {
  // Registered depth lies in the colour camera's image, so the colour field of view applies.
  const bool registered =
      device.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR;
  const openni::VideoStream& geometry = registered ? color : depth;
  const float hfov = geometry.getHorizontalFieldOfView();
  const float vfov = geometry.getVerticalFieldOfView();
  const openni::VideoMode mode = depth.getVideoMode();
  intrinsics.width = mode.getResolutionX();
  intrinsics.height = mode.getResolutionY();
  const double deg = kPi / 180.0;
  intrinsics.fx = FocalLength(intrinsics.width,
                              IsUsableFov(hfov) ? hfov : config.fallback_horizontal_fov_deg * deg);
  intrinsics.fy = FocalLength(intrinsics.height,
                              IsUsableFov(vfov) ? vfov : config.fallback_vertical_fov_deg * deg);
  intrinsics.cx = intrinsics.width / 2.0;
  intrinsics.cy = intrinsics.height / 2.0;
}

bool OpenNI2Source::Impl::Start(std::string* why) {
  // Frame sync is a convenience: without it pairs are still matched by timestamp.
  device.setDepthColorSyncEnabled(true);
  if (depth.start() != openni::STATUS_OK || color.start() != openni::STATUS_OK) {
    *why = description + ": cannot start the streams: " + ExtendedError();
    return false;
  }
  started = true;
  return true;
}

void OpenNI2Source::Impl::Close() {
  pending_depth.release();
  pending_color.release();
  if (started) {
    depth.stop();
    color.stop();
    std::this_thread::sleep_for(kDriverStopGrace);
    started = false;
  }
  depth.destroy();
  color.destroy();
  device.close();
  if (initialized) openni::OpenNI::shutdown();
  initialized = false;
}

// Waits for one frame of either stream and keeps it as that stream's pending frame.
FrameStatus OpenNI2Source::Impl::ReadOne(std::string* why) {
  if (IsFile() && depth_frames_read >= depth_frames_in_file &&
      color_frames_read >= color_frames_in_file) {
    return FrameStatus::kEnded;
  }
  openni::VideoStream* streams[] = {&depth, &color};
  int ready = -1;
  const int timeout_ms = first_frame ? config.open_timeout_ms : config.read_timeout_ms;
  const openni::Status status = openni::OpenNI::waitForAnyStream(streams, 2, &ready, timeout_ms);
  if (status == openni::STATUS_TIME_OUT) {
    // A recording that stops delivering has reached its end (frames the player dropped).
    if (IsFile()) return FrameStatus::kEnded;
    *why = "no frame within " + std::to_string(timeout_ms) + " ms";
    return FrameStatus::kFailed;
  }
  if (status != openni::STATUS_OK || ready < 0 || ready > 1) {
    *why = "waiting for frames failed: " + ExtendedError();
    return FrameStatus::kFailed;
  }
  openni::VideoFrameRef& pending = ready == 0 ? pending_depth : pending_color;
  if (streams[ready]->readFrame(&pending) != openni::STATUS_OK) {
    *why = "reading a frame failed: " + ExtendedError();
    return FrameStatus::kFailed;
  }
  ++(ready == 0 ? depth_frames_read : color_frames_read);
  first_frame = false;
  return FrameStatus::kFrame;
}

// Converts the pending pair into `frame` and releases it.
FrameStatus OpenNI2Source::Impl::MakeFrame(RgbdFrame* frame, std::string* why) {
  frame->frame_index = next_index++;
  frame->name = frame_prefix + " frame " + std::to_string(frame->frame_index);
  frame->stamp_s = static_cast<double>(pending_depth.getTimestamp()) * 1e-6;
  frame->intrinsics = intrinsics;
  frame->T_W_C = Eigen::Isometry3d::Identity();
  const bool converted =
      ConvertDepth(pending_depth, &frame->depth) && ConvertColor(pending_color, &frame->color);
  pending_depth.release();
  pending_color.release();
  if (!converted) {
    *why = "unsupported pixel format (depth: 1 mm or 100 um, colour: RGB888)";
    return FrameStatus::kFailed;
  }
  if (frame->depth.width != frame->color.width || frame->depth.height != frame->color.height ||
      frame->depth.width != intrinsics.width || frame->depth.height != intrinsics.height) {
    *why = frame->name + ": depth " + std::to_string(frame->depth.width) + "x" +
           std::to_string(frame->depth.height) + " and colour " +
           std::to_string(frame->color.width) + "x" + std::to_string(frame->color.height) +
           " differ from each other or from the stream's mode";
    return FrameStatus::kBadFrame;
  }
  return FrameStatus::kFrame;
}

OpenNI2Source::OpenNI2Source(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

OpenNI2Source::~OpenNI2Source() = default;

std::unique_ptr<OpenNI2Source> OpenNI2Source::Open(const OpenNI2SourceConfig& config,
                                                   std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  if (!impl->OpenDevice(why) || !impl->CreateStreams(why)) return nullptr;
  impl->ComputeIntrinsics();
  if (!impl->Start(why)) return nullptr;
  return std::unique_ptr<OpenNI2Source>(new OpenNI2Source(std::move(impl)));
}

FrameStatus OpenNI2Source::Next(RgbdFrame* frame, std::string* why) {
  Impl& impl = *impl_;
  const auto max_dt_us = static_cast<std::int64_t>(impl.config.max_pair_dt_s * 1e6);
  for (;;) {
    const FrameStatus status = impl.ReadOne(why);
    if (status != FrameStatus::kFrame) return status;
    if (!impl.pending_depth.isValid() || !impl.pending_color.isValid()) continue;
    const auto depth_us = static_cast<std::int64_t>(impl.pending_depth.getTimestamp());
    const auto color_us = static_cast<std::int64_t>(impl.pending_color.getTimestamp());
    if (std::abs(depth_us - color_us) <= max_dt_us) return impl.MakeFrame(frame, why);
    // No partner for the older frame will come any more: drop it and wait for a newer one.
    (depth_us < color_us ? impl.pending_depth : impl.pending_color).release();
  }
}

std::size_t OpenNI2Source::size() const {
  return static_cast<std::size_t>(std::max(impl_->depth_frames_in_file, 0));
}

std::string OpenNI2Source::Describe() const { return impl_->description; }

const CameraIntrinsics& OpenNI2Source::intrinsics() const { return impl_->intrinsics; }

}  // namespace objmap
