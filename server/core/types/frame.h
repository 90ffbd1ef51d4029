#pragma once
// Plain data types shared by every module. Only Eigen appears here: OpenCV, PCL and OctoMap
// stay inside the modules that use them, which keeps public headers light to compile.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace objmap {

using KeyframeId = std::int64_t;
using ObjectId = std::int64_t;

/// Poses farther than this from the map origin are refused: float map coordinates (object
/// models, voxel keys) keep centimetres only within about 100 km.
inline constexpr double kMaxTranslationM = 1e5;
/// Depths beyond this are no measurement (no RGB-D sensor reaches it; a driver's 1e30 would
/// overflow the voxel keys of the rays).
inline constexpr double kMaxDepthM = 1000.0;
/// Focal lengths are refused outside [kMinFocalPx, kMaxFocalPx]: a lens of 1e5 px on a 640 px
/// image sees 0.4 degrees, and larger values overflow pixel arithmetic.
inline constexpr double kMinFocalPx = 1.0;
inline constexpr double kMaxFocalPx = 1e5;

/// Pinhole intrinsics of the depth camera. Colour images are assumed to share the geometry
/// (7-Scenes is not registered: offsets of 10-20 px are absorbed downstream).
struct CameraIntrinsics {
  int width = 640;    ///< image width in pixels
  int height = 480;   ///< image height in pixels
  double fx = 585.0;  ///< focal length x in pixels
  double fy = 585.0;  ///< focal length y in pixels
  double cx = 320.0;  ///< principal point x in pixels
  double cy = 240.0;  ///< principal point y in pixels

  /// True when sizes are positive, focal lengths within [kMinFocalPx, kMaxFocalPx] and the
  /// principal point within one image size of the image; otherwise names the field.
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Row-major 8-bit RGB image (3 bytes per pixel).
struct ColorImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;

  [[nodiscard]] bool empty() const { return width <= 0 || height <= 0 || rgb.empty(); }
};

/// Row-major depth image in metres; 0 (or NaN) marks an invalid pixel.
struct DepthImage {
  int width = 0;
  int height = 0;
  std::vector<float> depth_m;

  [[nodiscard]] bool empty() const { return width <= 0 || height <= 0 || depth_m.empty(); }
};

/// One RGB-D frame with its camera-to-world pose.
struct RgbdFrame {
  std::int64_t frame_index = 0;  ///< index within its sequence
  double stamp_s = 0.0;          ///< timestamp in seconds (0 when the source has none)
  std::string name;              ///< human-readable origin, used in error messages
  ColorImage color;
  DepthImage depth;
  CameraIntrinsics intrinsics;
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< maps camera points into the world
};

/// True when every entry is finite, the rotation is orthonormal with det +1 (within tolerance),
/// the translation within kMaxTranslationM and the last row is (0 0 0 1); otherwise says what is
/// wrong.
[[nodiscard]] bool IsValidRigidTransform(const Eigen::Matrix4d& T, std::string* why);

/// Checks image sizes against the intrinsics and the pose; names the problem on failure.
[[nodiscard]] bool ValidateFrame(const RgbdFrame& frame, std::string* why);

}  // namespace objmap
