#include "sim/object_meshes.h"

#include <algorithm>
#include <filesystem>
#include <map>

#include "sim/furniture_catalog.h"

namespace objmap::sim {
namespace {

// Catalog names that may stand in for a procedural object of each class.
const std::map<std::string, std::vector<std::string>>& CatalogNames() {
  static const std::map<std::string, std::vector<std::string>> names = {
      {"dining table", {"Table", "Wooden table", "Technical table", "Wooden teak table"}},
      {"chair", {"Chair", "Chair with cushion", "Folding chair"}},
      {"tv", {"TV", "TV 16:9", "Wall flat TV"}},
      {"cup", {"Coffee mug", "Plastic cup"}},
      {"book", {"Book"}},
      {"laptop", {"Laptop"}},
      {"potted plant", {"Plant", "Decorative plant", "Spider plant", "Succulent plant"}},
      {"sink", {"Sink"}},
      {"microwave", {"Microwave"}},
      {"oven", {"Small oven"}},
      {"refrigerator", {"Refrigerator"}},
      {"bottle", {"Bottle", "Wine bottle"}}};
  return names;
}

}  // namespace

Rgb Jitter(const Rgb& color, Random* random) {
  Rgb out;
  for (int c = 0; c < 3; ++c) {
    out[c] =
        static_cast<std::uint8_t>(std::clamp(color[c] + random->Uniform(-20.0, 20.0), 0.0, 255.0));
  }
  return out;
}

// Objects stand on z = 0 of their frame, centred on x = y = 0 unless said otherwise.

TriangleMesh TableMesh(float length, float width, float height, const Rgb& wood) {
  TriangleMesh mesh;
  const float top = 0.03f, leg = 0.05f;
  mesh.AddBox({-length / 2, -width / 2, height - top}, {length / 2, width / 2, height}, wood);
  for (float sx : {-1.f, 1.f}) {
    for (float sy : {-1.f, 1.f}) {
      const Eigen::Vector3f c(sx * (length / 2 - leg), sy * (width / 2 - leg), 0.f);
      mesh.AddBox(c - Eigen::Vector3f(leg / 2, leg / 2, 0.f),
                  c + Eigen::Vector3f(leg / 2, leg / 2, height - top), wood);
    }
  }
  return mesh;
}

// Seat 0.45 m high; the back is on the +y side.
TriangleMesh ChairMesh(const Rgb& color) {
  TriangleMesh mesh;
  const float seat = 0.45f, half = 0.22f, leg = 0.035f;
  mesh.AddBox({-half, -half, seat - 0.04f}, {half, half, seat}, color);
  mesh.AddBox({-half, half - 0.04f, seat}, {half, half, seat + 0.45f}, color);
  for (float sx : {-1.f, 1.f}) {
    for (float sy : {-1.f, 1.f}) {
      const Eigen::Vector3f c(sx * (half - leg), sy * (half - leg), 0.f);
      mesh.AddBox(c - Eigen::Vector3f(leg / 2, leg / 2, 0.f),
                  c + Eigen::Vector3f(leg / 2, leg / 2, seat - 0.04f), color);
    }
  }
  return mesh;
}

// A flat screen on a stand; the screen faces -y.
TriangleMesh MonitorMesh(float width, float height, const Rgb& frame, const Rgb& screen) {
  TriangleMesh mesh;
  mesh.AddBox({-0.12f, -0.1f, 0.f}, {0.12f, 0.1f, 0.015f}, frame);       // foot
  mesh.AddBox({-0.025f, 0.02f, 0.015f}, {0.025f, 0.05f, 0.12f}, frame);  // neck
  mesh.AddBox({-width / 2, -0.01f, 0.1f}, {width / 2, 0.03f, 0.1f + height}, frame);
  mesh.AddBox({-width / 2 + 0.015f, -0.012f, 0.115f}, {width / 2 - 0.015f, -0.01f, 0.085f + height},
              screen);
  return mesh;
}

// A computer keyboard: a flat slab with a relief of keys (the paper's flat-keyboard case).
TriangleMesh KeyboardMesh(const Rgb& body, const Rgb& keys) {
  TriangleMesh mesh;
  const float length = 0.44f, depth = 0.14f;
  mesh.AddBox({-length / 2, -depth / 2, 0.f}, {length / 2, depth / 2, 0.015f}, body);
  const int columns = 15, rows = 5;
  const float pitch_x = (length - 0.03f) / columns, pitch_y = (depth - 0.02f) / rows;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const Eigen::Vector3f corner(-length / 2 + 0.015f + c * pitch_x,
                                   -depth / 2 + 0.01f + r * pitch_y, 0.015f);
      mesh.AddBox(corner + Eigen::Vector3f(0.002f, 0.002f, 0.f),
                  corner + Eigen::Vector3f(pitch_x - 0.002f, pitch_y - 0.002f, 0.008f), keys);
    }
  }
  return mesh;
}

TriangleMesh MouseMesh(const Rgb& color) {
  TriangleMesh mesh;
  mesh.AddBox({-0.03f, -0.055f, 0.f}, {0.03f, 0.055f, 0.035f}, color);
  return mesh;
}

TriangleMesh CupMesh(const Rgb& color) {
  TriangleMesh mesh;
  mesh.AddCylinder({0.f, 0.f, 0.f}, 0.04f, 0.1f, 16, color);
  mesh.AddBox({0.04f, -0.006f, 0.025f}, {0.065f, 0.006f, 0.075f}, color);  // handle
  return mesh;
}

TriangleMesh BookMesh(float length, float width, float thickness, const Rgb& color) {
  TriangleMesh mesh;
  mesh.AddBox({-length / 2, -width / 2, 0.f}, {length / 2, width / 2, thickness}, color);
  return mesh;
}

TriangleMesh LaptopMesh(const Rgb& color, const Rgb& screen) {
  TriangleMesh mesh;
  mesh.AddBox({-0.17f, -0.12f, 0.f}, {0.17f, 0.12f, 0.02f}, color);
  // The lid, opened to about 105 degrees, hinged at the back edge.
  TriangleMesh lid;
  lid.AddBox({-0.17f, 0.f, 0.f}, {0.17f, 0.23f, 0.012f}, color);
  lid.AddBox({-0.16f, 0.01f, -0.001f}, {0.16f, 0.22f, 0.f}, screen);
  Eigen::Isometry3f hinge = Eigen::Isometry3f::Identity();
  hinge.translate(Eigen::Vector3f(0.f, 0.12f, 0.02f));
  hinge.rotate(Eigen::AngleAxisf(1.83f, Eigen::Vector3f::UnitX()));
  mesh.Append(lid, hinge);
  return mesh;
}

TriangleMesh BottleMesh(const Rgb& color) {
  TriangleMesh mesh;
  mesh.AddCylinder({0.f, 0.f, 0.f}, 0.035f, 0.2f, 12, color);
  mesh.AddCylinder({0.f, 0.f, 0.2f}, 0.014f, 0.08f, 8, color);
  return mesh;
}

// A box appliance standing on z = 0 with a darker front panel (door, window) facing -y.
TriangleMesh ApplianceMesh(float width, float depth, float height, const Rgb& body,
                           const Rgb& front) {
  TriangleMesh mesh;
  mesh.AddBox({-width / 2, -depth / 2, 0.f}, {width / 2, depth / 2, height}, body);
  mesh.AddBox({-width / 2 + 0.03f, -depth / 2 - 0.005f, 0.04f},
              {width / 2 - 0.03f, -depth / 2, height - 0.04f}, front);
  return mesh;
}

// A sink basin: a rim around a recess, set into a counter top.
TriangleMesh SinkMesh(const Rgb& steel) {
  TriangleMesh mesh;
  const float w = 0.6f, d = 0.45f, rim = 0.04f, depth = 0.15f;
  mesh.AddBox({-w / 2, -d / 2, -depth}, {w / 2, d / 2, -depth + 0.01f}, steel);  // bottom
  mesh.AddBox({-w / 2, -d / 2, -depth}, {-w / 2 + rim, d / 2, 0.01f}, steel);
  mesh.AddBox({w / 2 - rim, -d / 2, -depth}, {w / 2, d / 2, 0.01f}, steel);
  mesh.AddBox({-w / 2, -d / 2, -depth}, {w / 2, -d / 2 + rim, 0.01f}, steel);
  mesh.AddBox({-w / 2, d / 2 - rim, -depth}, {w / 2, d / 2, 0.01f}, steel);
  mesh.AddCylinder({0.f, d / 2 - 0.05f, 0.01f}, 0.015f, 0.25f, 8, steel);  // tap
  return mesh;
}

TriangleMesh PottedPlantMesh() {
  TriangleMesh mesh;
  mesh.AddCylinder({0.f, 0.f, 0.f}, 0.12f, 0.3f, 12, {150, 80, 50});
  mesh.AddCylinder({0.f, 0.f, 0.3f}, 0.22f, 0.5f, 10, {40, 130, 50});
  return mesh;
}

TriangleMesh DressFromCatalog(const FurnitureCatalog* catalog, const std::string& class_name,
                              const TriangleMesh& procedural, std::uint64_t seed, int id,
                              const std::vector<std::string>* mesh_names, std::string* name) {
  const auto names = CatalogNames().find(class_name);
  if (catalog == nullptr || (mesh_names == nullptr && names == CatalogNames().end())) {
    return procedural;
  }
  std::vector<const FurnitureEntry*> candidates =
      catalog->Named(mesh_names != nullptr ? *mesh_names : names->second);
  candidates.erase(
      std::remove_if(candidates.begin(), candidates.end(),
                     [](const FurnitureEntry* e) { return e->category == "Exterior"; }),
      candidates.end());
  if (candidates.empty()) return procedural;
  Random pick(seed, 0xCA7A106ull, static_cast<std::uint64_t>(id));
  const FurnitureEntry& entry = *candidates[pick.Next() % candidates.size()];
  TriangleMesh mesh;
  std::string why;
  if (!catalog->LoadMesh(entry, &mesh, &why)) return procedural;
  Eigen::Vector3f want_min, want_max, have_min, have_max;
  procedural.Bounds(&want_min, &want_max);
  mesh.Bounds(&have_min, &have_max);
  const Eigen::Vector3f scale =
      (want_max - want_min).cwiseQuotient((have_max - have_min).cwiseMax(1e-6f));
  for (Eigen::Vector3f& v : mesh.vertices) v = want_min + (v - have_min).cwiseProduct(scale);
  *name += " (" + entry.name + " by " + entry.creator + ", " +
           std::filesystem::path(entry.archive).filename().string() + ")";
  return mesh;
}

}  // namespace objmap::sim
