#pragma once
// Synthetic indoor scenes for ground truth: triangle meshes of COCO objects placed in a room,
// with a camera trajectory. Procedural objects (boxes, prisms) stand in where no mesh is given;
// every scene is a pure function of its kind and seed.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "types/frame.h"

namespace objmap::sim {

using Rgb = std::array<std::uint8_t, 3>;

/// An RGB image repeated over texture coordinates (u, v), one repeat per unit; v runs upwards,
/// as in OBJ files.
struct Texture {
  int width = 0, height = 0;
  std::vector<Rgb> texels;  ///< row-major, top row first

  /// The texel at (u, v) (nearest), black when the texture is empty.
  [[nodiscard]] Rgb Sample(const Eigen::Vector2f& uv) const;
};

/// Triangles with one colour each, some of them textured per pixel.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;
  /// One per triangle; a textured triangle's is its texture's colour at its centre.
  std::vector<Rgb> colors;
  /// Per-pixel texturing: empty (no triangle textured), or one entry per triangle, an index into
  /// `textures` (-1: the plain colour), with the texture coordinates of its three corners in
  /// `corner_uvs`. Textures are shared between copies of a mesh.
  std::vector<int> texture_of;
  std::vector<std::array<Eigen::Vector2f, 3>> corner_uvs;
  std::vector<std::shared_ptr<const Texture>> textures;

  /// An axis-aligned box [min, max] (in the mesh frame, then moved by `T`), outward faces.
  void AddBox(const Eigen::Vector3f& min, const Eigen::Vector3f& max, const Rgb& color,
              const Eigen::Isometry3f& T = Eigen::Isometry3f::Identity());
  /// A vertical prism of `sides` sides around the z axis (a cylinder for large `sides`): radius,
  /// from z0 to z1, with top and bottom caps.
  void AddCylinder(const Eigen::Vector3f& base_centre, float radius, float height, int sides,
                   const Rgb& color);
  /// Appends `other` moved by `T`.
  void Append(const TriangleMesh& other,
              const Eigen::Isometry3f& T = Eigen::Isometry3f::Identity());
  /// Points sampled uniformly on the surface (area-weighted), deterministic for `seed`.
  [[nodiscard]] std::vector<Eigen::Vector3f> SampleSurface(std::size_t count,
                                                           std::uint64_t seed) const;
  /// Axis-aligned bounds of the vertices.
  void Bounds(Eigen::Vector3f* min, Eigen::Vector3f* max) const;

  /// The texture of triangle `t`, or nullptr when it has the plain colour.
  [[nodiscard]] const Texture* TextureOf(std::size_t t) const;

 private:
  // Gives the triangles added since the last call "no texture" entries, once some are textured.
  void PadTextures();
};

/// One real object: its mesh in its own frame and where it stands.
struct SceneObject {
  int id = 0;  ///< instance id (1..), as in the rendered instance images
  int class_id = -1;
  std::string name;   ///< what it is ("left monitor"), for people reading ground_truth.json
  TriangleMesh mesh;  ///< object frame
  Eigen::Isometry3d T_W_O = Eigen::Isometry3d::Identity();
};

struct Scene {
  std::string kind;
  std::uint64_t seed = 0;
  TriangleMesh structure;  ///< room and everything that is no COCO object (world frame)
  std::vector<SceneObject> objects;
  CameraIntrinsics intrinsics;
  std::vector<Eigen::Isometry3d> trajectory;  ///< T_W_C per frame
};

/// The scene kinds there are: "desk", "office", "kitchen", "lab" (the paper's four sequences).
[[nodiscard]] std::vector<std::string> SceneKinds();

class FurnitureCatalog;

/// A scene of `kind` with `frames` camera poses; positions, sizes and colours vary with `seed`.
/// The paper's hard cases are in it: monitors side by side, a flat keyboard on the desk, stacked
/// books, cups close together, a chair pushed under the desk. With a `catalog`, tables, chairs,
/// monitors, cups, books, laptops and plants are real furniture meshes (picked by seed, scaled
/// into the place of the procedural ones); keyboards and mice stay procedural (the catalog's
/// keyboard is a musical one). False with a reason for an unknown kind.
[[nodiscard]] bool MakeScene(const std::string& kind, std::uint64_t seed, int frames, Scene* scene,
                             std::string* why, const FurnitureCatalog* catalog = nullptr);

/// A scene from a file instead of a kind and a seed:
///   {"kind": "my-office", "seed": 3, "room": [5, 4.5, 2.7],
///    "objects": [{"class": "cup", "mesh": "Coffee mug", "position": [2.1, 3.2, 0.74],
///                 "yaw_deg": 30, "size": [0.12, 0.08, 0.1], "name": "my mug"}, ...],
///    "camera": {"target": [2.3, 3.2, 0.8], "radius": 1.7, "frames": 300}}
/// Positions are the objects' base centres (metres); "mesh" names a catalog model (used when the
/// catalog has it, scaled to "size"; otherwise a box of "size" stands in); "size" may be left
/// out when the catalog has the mesh. The camera sweeps an arc in front of the target, or, with
///    "camera": {"waypoints": [{"eye": [x, y, z], "target": [x, y, z]}, ...], "frames": 300},
/// follows the waypoints: frames spread evenly over them, eye and target moving in straight
/// lines, the camera upright and looking at the target.
[[nodiscard]] bool MakeSceneFromFile(const std::string& path, const FurnitureCatalog* catalog,
                                     Scene* scene, std::string* why);

}  // namespace objmap::sim
