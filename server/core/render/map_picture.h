#pragma once
// A picture of an object map, like the figures of object-mapping papers: the structure (the
// occupied voxels) in grey shaded by height, each object's point model in its class colour with a
// label (class, id, confidence), a legend of the classes with their counts and a scale bar.
// Rendered on the CPU into an RGB buffer (splatted points, a depth buffer, eye-dome shading from
// the depth): no display and no GPU needed.

#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "types/frame.h"

namespace objmap {

using RgbColour = std::array<std::uint8_t, 3>;

/// One object of the picture: its model and what its label says.
struct PictureObject {
  ObjectId id = 0;
  std::string class_name;
  float confidence = 0.f;
  std::vector<Eigen::Vector3f> points_W;
};

/// What the picture shows, in world coordinates.
struct PictureScene {
  /// Centres of the occupied structure voxels, each drawn as a cube of structure_voxel_m.
  std::vector<Eigen::Vector3f> structure_W;
  float structure_voxel_m = 0.01f;
  /// Inventory objects; their points are drawn as cubes of object_voxel_m.
  std::vector<PictureObject> objects;
  float object_voxel_m = 0.005f;
};

enum class PictureView {
  kTop,          ///< straight down along -up, framing the content
  kPerspective,  ///< from above one side, looking at the content's centre
  kCamera,       ///< from PictureConfig::T_W_C
};

[[nodiscard]] const char* PictureViewName(PictureView view);
/// "top", "perspective" or "camera"; false for anything else.
[[nodiscard]] bool ParsePictureView(const std::string& name, PictureView* view);

struct PictureConfig {
  int width = 1280;
  int height = 960;
  PictureView view = PictureView::kPerspective;
  /// kCamera: the camera's pose (camera frame: x right, y down, z forward).
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  /// Vertical field of view of the perspective and camera views; the top view uses a narrower
  /// one (top_fov_deg) from farther away, near an orthographic map.
  double fov_deg = 50.0;
  double top_fov_deg = 30.0;
  /// The world's up direction: heights shade the structure, the top view looks down it and the
  /// perspective view keeps it up in the picture. A map has no gravity of its own; the caller
  /// gives it (UpFromCameras: cameras are held upright).
  Eigen::Vector3d up_W = Eigen::Vector3d::UnitZ();
  /// Only objects of this class are coloured, labelled and framed ("": every class); the others
  /// are drawn as structure.
  std::string only_class;
  /// Only what lies inside this box is drawn, and the view frames it.
  std::optional<Eigen::AlignedBox3f> region;
  bool labels = true;
  bool legend = true;
  bool scale_bar = true;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// The pinhole camera a picture was rendered with, for projecting world points into it.
struct PictureCamera {
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;

  /// Pixel (u right, v down) of a world point; nullopt behind the camera.
  [[nodiscard]] std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& point_W) const;
};

struct LegendEntry {
  std::string class_name;
  int count = 0;
  RgbColour colour{};
};

struct MapPicture {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< row-major, 3 bytes a pixel
  PictureCamera camera;
  /// Classes shown, most objects first (then by name), with their colour.
  std::vector<LegendEntry> legend;
  /// The scale bar's length (0 without one) and its pixels, at the depth of the view's centre.
  double scale_bar_m = 0.0;
  int scale_bar_px = 0;
};

/// The colour of a class in every picture: a fixed qualitative palette by COCO class, a neutral
/// violet for objects no detector named, saturated so that no class looks like the grey
/// structure.
[[nodiscard]] RgbColour ClassColour(const std::string& class_name);

/// Renders `scene` as `config` says. False with the reason when the config is invalid or nothing
/// is left to show (an empty map, a class or region with nothing in it).
[[nodiscard]] bool RenderMapPicture(const PictureScene& scene, const PictureConfig& config,
                                    MapPicture* picture, std::string* why);

/// Writes the picture as a PNG file.
[[nodiscard]] bool WritePicturePng(const MapPicture& picture, const std::string& path,
                                   std::string* why);

/// The world's up direction from camera poses: cameras on robots and in hands are rarely rolled,
/// so their image-right axes are horizontal (whatever their pitch) and up is the direction most
/// perpendicular to them, on the side of their image-up axes (-y). nullopt without poses or when
/// the image-up axes disagree too much to give a side (their mean shorter than half a unit).
[[nodiscard]] std::optional<Eigen::Vector3d> UpFromCameras(
    const std::vector<Eigen::Isometry3d>& T_W_C);

}  // namespace objmap
