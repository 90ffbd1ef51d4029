#include "sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/sim_random.h"

namespace objmap::sim {
namespace {

constexpr float kNearM = 0.05f;

struct Buffers {
  int width = 0, height = 0;
  std::vector<float> z;  // camera-frame depth, +inf where empty
  std::vector<std::uint16_t> id;
  std::vector<Rgb> color;
  std::vector<Eigen::Vector3f> normal;  // camera frame, unit, towards the camera
};

// A corner of a triangle in the camera frame with its texture coordinates.
struct Corner {
  Eigen::Vector3f p;
  Eigen::Vector2f uv;
};

// Keeps the part of a polygon with z >= kNearM (Sutherland-Hodgman against one plane).
std::vector<Corner> ClipNear(const std::vector<Corner>& polygon) {
  std::vector<Corner> out;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Corner& a = polygon[i];
    const Corner& b = polygon[(i + 1) % polygon.size()];
    const bool a_in = a.p.z() >= kNearM, b_in = b.p.z() >= kNearM;
    if (a_in) out.push_back(a);
    if (a_in != b_in) {
      const float t = (kNearM - a.p.z()) / (b.p.z() - a.p.z());
      out.push_back({a.p + (b.p - a.p) * t, a.uv + (b.uv - a.uv) * t});
    }
  }
  return out;
}

// What a triangle looks like: its plain colour, or its texture sampled per pixel.
struct Look {
  Rgb color;
  const Texture* texture = nullptr;
};

void FillTriangle(const Corner& c0, const Corner& c1, const Corner& c2,
                  const Eigen::Vector3f& normal, std::uint16_t id, const Look& look,
                  const CameraIntrinsics& K, Buffers* b) {
  const Eigen::Vector3f &p0 = c0.p, &p1 = c1.p, &p2 = c2.p;
  auto project = [&](const Eigen::Vector3f& p) {
    return Eigen::Vector2f(static_cast<float>(K.fx) * p.x() / p.z() + static_cast<float>(K.cx),
                           static_cast<float>(K.fy) * p.y() / p.z() + static_cast<float>(K.cy));
  };
  const Eigen::Vector2f s0 = project(p0), s1 = project(p1), s2 = project(p2);
  const float area = (s1 - s0).x() * (s2 - s0).y() - (s1 - s0).y() * (s2 - s0).x();
  if (std::abs(area) < 1e-9f) return;
  const int u_min = std::max(0, static_cast<int>(std::ceil(std::min({s0.x(), s1.x(), s2.x()}))));
  const int u_max =
      std::min(b->width - 1, static_cast<int>(std::floor(std::max({s0.x(), s1.x(), s2.x()}))));
  const int v_min = std::max(0, static_cast<int>(std::ceil(std::min({s0.y(), s1.y(), s2.y()}))));
  const int v_max =
      std::min(b->height - 1, static_cast<int>(std::floor(std::max({s0.y(), s1.y(), s2.y()}))));
  const float inv_z0 = 1.f / p0.z(), inv_z1 = 1.f / p1.z(), inv_z2 = 1.f / p2.z();
  for (int v = v_min; v <= v_max; ++v) {
    for (int u = u_min; u <= u_max; ++u) {
      const Eigen::Vector2f s(static_cast<float>(u), static_cast<float>(v));
      // Barycentric weights from edge functions; a pixel on an edge belongs to the triangle.
      const float w0 = ((s1 - s).x() * (s2 - s).y() - (s1 - s).y() * (s2 - s).x()) / area;
      const float w1 = ((s2 - s).x() * (s0 - s).y() - (s2 - s).y() * (s0 - s).x()) / area;
      const float w2 = 1.f - w0 - w1;
      if (w0 < 0.f || w1 < 0.f || w2 < 0.f) continue;
      // 1/z is linear in screen space, and so is uv/z (perspective-correct texturing).
      const float z = 1.f / (w0 * inv_z0 + w1 * inv_z1 + w2 * inv_z2);
      const std::size_t i = static_cast<std::size_t>(v) * b->width + u;
      if (z >= b->z[i]) continue;
      b->z[i] = z;
      b->id[i] = id;
      b->color[i] = look.texture == nullptr
                        ? look.color
                        : look.texture->Sample(z * (w0 * inv_z0 * c0.uv + w1 * inv_z1 * c1.uv +
                                                    w2 * inv_z2 * c2.uv));
      b->normal[i] = normal;
    }
  }
}

void DrawMesh(const TriangleMesh& mesh, const Eigen::Isometry3f& T_C_M, std::uint16_t id,
              const CameraIntrinsics& K, Buffers* b) {
  std::vector<Eigen::Vector3f> camera(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) camera[i] = T_C_M * mesh.vertices[i];
  const Eigen::Vector2f no_uv = Eigen::Vector2f::Zero();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f &a = camera[tri[0]], &c1 = camera[tri[1]], &c2 = camera[tri[2]];
    Eigen::Vector3f normal = (c1 - a).cross(c2 - a);
    if (normal.squaredNorm() < 1e-20f) continue;
    normal.normalize();
    // Both sides are drawn (catalog meshes are not all closed or consistently wound); the
    // normal is turned towards the camera for shading and the incidence test.
    if (normal.dot(a) > 0.f) normal = -normal;
    const Look look{mesh.colors[t], mesh.TextureOf(t)};
    const bool textured = look.texture != nullptr;
    const std::vector<Corner> polygon = ClipNear({{a, textured ? mesh.corner_uvs[t][0] : no_uv},
                                                  {c1, textured ? mesh.corner_uvs[t][1] : no_uv},
                                                  {c2, textured ? mesh.corner_uvs[t][2] : no_uv}});
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
      FillTriangle(polygon[0], polygon[k], polygon[k + 1], normal, id, look, K, b);
    }
  }
}

}  // namespace

bool DepthNoiseConfig::IsValid(std::string* why) const {
  if (!(axial_a_m >= 0.0) || !(axial_b_per_m >= 0.0) || !(baseline_m > 0.0) ||
      disparity_subpixels < 0 || !(min_depth_m >= 0.0) || !(max_depth_m > min_depth_m) ||
      !(max_incidence_deg > 0.0 && max_incidence_deg <= 90.0) || !(edge_jump_fraction > 0.0) ||
      !(edge_dropout_probability >= 0.0 && edge_dropout_probability <= 1.0)) {
    *why =
        "DepthNoiseConfig: noise terms >= 0, baseline_m > 0, disparity_subpixels >= 0, "
        "0 <= min_depth_m < max_depth_m, "
        "max_incidence_deg in (0, 90], edge_jump_fraction > 0, edge_dropout_probability in "
        "[0, 1] are required";
    return false;
  }
  return true;
}

RenderedFrame Render(const Scene& scene, const Eigen::Isometry3d& T_W_C,
                     const DepthNoiseConfig& noise, std::uint64_t seed, int frame_index) {
  const CameraIntrinsics& K = scene.intrinsics;
  Buffers b;
  b.width = K.width;
  b.height = K.height;
  const std::size_t n = static_cast<std::size_t>(K.width) * K.height;
  b.z.assign(n, std::numeric_limits<float>::infinity());
  b.id.assign(n, 0);
  b.color.assign(n, Rgb{0, 0, 0});
  b.normal.assign(n, Eigen::Vector3f::Zero());
  const Eigen::Isometry3d T_C_W = T_W_C.inverse();
  DrawMesh(scene.structure, T_C_W.cast<float>(), 0, K, &b);
  for (const SceneObject& object : scene.objects) {
    DrawMesh(object.mesh, (T_C_W * object.T_W_O).cast<float>(),
             static_cast<std::uint16_t>(object.id), K, &b);
  }

  RenderedFrame frame;
  frame.color.width = frame.depth.width = K.width;
  frame.color.height = frame.depth.height = K.height;
  frame.color.rgb.assign(3 * n, 0);
  frame.depth.depth_m.assign(n, 0.f);
  frame.true_depth_m.assign(n, 0.f);
  frame.instance = b.id;
  const double cos_limit = std::cos(noise.max_incidence_deg * M_PI / 180.0);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * K.width + u;
      if (!std::isfinite(b.z[i])) continue;
      const float z = b.z[i];
      const Eigen::Vector3f ray = Eigen::Vector3f(static_cast<float>((u - K.cx) / K.fx),
                                                  static_cast<float>((v - K.cy) / K.fy), 1.f)
                                      .normalized();
      const double incidence = std::abs(static_cast<double>(b.normal[i].dot(ray)));
      // Headlight shading: surfaces facing the camera are brightest.
      const double light = 0.35 + 0.65 * incidence;
      for (int c = 0; c < 3; ++c) {
        frame.color.rgb[3 * i + c] = static_cast<std::uint8_t>(std::lround(b.color[i][c] * light));
      }
      frame.true_depth_m[i] = z;
      if (!noise.enabled) {
        frame.depth.depth_m[i] = z;
        continue;
      }
      if (z < noise.min_depth_m || z > noise.max_depth_m || incidence < cos_limit) continue;
      Random random(seed, static_cast<std::uint64_t>(frame_index), i);
      bool edge = false;
      for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int nu = u + du, nv = v + dv;
        if (nu < 0 || nv < 0 || nu >= K.width || nv >= K.height) continue;
        const float other = b.z[static_cast<std::size_t>(nv) * K.width + nu];
        if (!std::isfinite(other) || std::abs(other - z) > noise.edge_jump_fraction * z)
          edge = true;
      }
      if (edge && random.Uniform() < noise.edge_dropout_probability) continue;
      const double sigma =
          noise.axial_a_m + noise.axial_b_per_m * (z - noise.axial_z0_m) * (z - noise.axial_z0_m);
      double measured = z + sigma * random.Normal();
      if (noise.disparity_subpixels > 0) {
        const double fb = K.fx * noise.baseline_m;
        const double steps = std::round(noise.disparity_subpixels * fb / measured);
        measured = steps > 0.0 ? noise.disparity_subpixels * fb / steps : 0.0;
      }
      frame.depth.depth_m[i] = static_cast<float>(measured);
    }
  }
  return frame;
}

}  // namespace objmap::sim
