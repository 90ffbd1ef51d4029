#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "sim/furniture_catalog.h"
#include "sim/object_meshes.h"
#include "sim/sim_random.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

constexpr float kPi = 3.14159265f;

Eigen::Isometry3f Pose(const Eigen::Vector3f& t, float yaw = 0.f) {
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.translate(t);
  T.rotate(Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()));
  return T;
}

class SceneBuilder {
 public:
  SceneBuilder(Scene* scene, Random* random, const FurnitureCatalog* catalog)
      : scene_(scene), random_(random), catalog_(catalog) {}
  // Adds an object; with a catalog, a real mesh of its class scaled into the procedural mesh's
  // bounds replaces it (the procedural one stays when none loads).
  // `mesh_names` (optional) replaces the class's catalog names.
  void Add(const std::string& class_name, const std::string& name, const TriangleMesh& mesh,
           const Eigen::Vector3f& position, float yaw,
           const std::vector<std::string>* mesh_names = nullptr) {
    SceneObject object;
    object.id = static_cast<int>(scene_->objects.size()) + 1;
    object.class_id = CocoClassId(class_name);
    object.name = name;
    // The pick has a random stream of its own, so that dressing a scene moves nothing in it.
    object.mesh = DressFromCatalog(catalog_, class_name, mesh, scene_->seed, object.id, mesh_names,
                                   &object.name);
    object.T_W_O = Pose(position, yaw).cast<double>();
    scene_->objects.push_back(std::move(object));
  }
  Random& random() { return *random_; }
  Scene& scene() { return *scene_; }

 private:
  Scene* scene_;
  Random* random_;
  const FurnitureCatalog* catalog_;
};

// Floor, walls and a ceiling of a w x d x h room with its corner at the origin.
void AddRoom(float w, float d, float h, Random* random, TriangleMesh* structure) {
  const Rgb floor = Jitter({120, 110, 100}, random), wall = Jitter({215, 210, 200}, random);
  structure->AddBox({0.f, 0.f, -0.05f}, {w, d, 0.f}, floor);
  structure->AddBox({0.f, 0.f, h}, {w, d, h + 0.05f}, wall);
  structure->AddBox({-0.05f, 0.f, 0.f}, {0.f, d, h}, wall);
  structure->AddBox({w, 0.f, 0.f}, {w + 0.05f, d, h}, wall);
  structure->AddBox({0.f, -0.05f, 0.f}, {w, 0.f, h}, wall);
  structure->AddBox({0.f, d, 0.f}, {w, d + 0.05f, h}, wall);
}

// The desk with everything on it, its front edge facing -y, centred at `centre` (floor level).
void AddDesk(SceneBuilder* b, const Eigen::Vector3f& centre, bool two_monitors) {
  Random& r = b->random();
  const float height = 0.74f, length = 1.6f, width = 0.8f;
  b->Add("dining table", "desk", TableMesh(length, width, height, Jitter({170, 130, 90}, &r)),
         centre, 0.f);
  const Eigen::Vector3f top = centre + Eigen::Vector3f(0.f, 0.f, height);
  const Rgb black = Jitter({40, 40, 45}, &r), screen = Jitter({30, 60, 120}, &r);
  if (two_monitors) {
    // Side by side, a centimetre apart: the paper's "two monitors merged into one".
    const float w = static_cast<float>(r.Uniform(0.5, 0.56));
    b->Add("tv", "left monitor", MonitorMesh(w, 0.32f, black, screen),
           top + Eigen::Vector3f(-w / 2 - 0.005f, 0.2f, 0.f), 0.f);
    b->Add("tv", "right monitor", MonitorMesh(w, 0.32f, black, screen),
           top + Eigen::Vector3f(w / 2 + 0.005f, 0.2f, 0.f), 0.f);
  } else {
    b->Add("laptop", "laptop", LaptopMesh(Jitter({150, 150, 155}, &r), screen),
           top + Eigen::Vector3f(0.f, 0.12f, 0.f), static_cast<float>(r.Uniform(-0.2, 0.2)));
  }
  b->Add("keyboard", "keyboard", KeyboardMesh(black, Jitter({70, 70, 75}, &r)),
         top + Eigen::Vector3f(static_cast<float>(r.Uniform(-0.1, 0.05)), -0.16f, 0.f),
         static_cast<float>(r.Uniform(-0.08, 0.08)));
  b->Add("mouse", "mouse", MouseMesh(black), top + Eigen::Vector3f(0.33f, -0.17f, 0.f), 0.f);
  // Two cups close together (3 cm apart) at the left end.
  const Eigen::Vector3f cups = top + Eigen::Vector3f(-0.62f, -0.15f, 0.f);
  b->Add("cup", "left cup", CupMesh(Jitter({230, 230, 225}, &r)), cups, 0.4f);
  b->Add("cup", "right cup", CupMesh(Jitter({180, 40, 40}, &r)),
         cups + Eigen::Vector3f(0.11f, 0.f, 0.f), 2.6f);
  // Three books stacked at the right end.
  float z = 0.f;
  for (int i = 0; i < 3; ++i) {
    const float thickness = static_cast<float>(r.Uniform(0.02, 0.04));
    b->Add("book", "book " + std::to_string(i + 1),
           BookMesh(0.24f - 0.02f * i, 0.17f, thickness,
                    Jitter({static_cast<std::uint8_t>(60 + 60 * i), 90,
                            static_cast<std::uint8_t>(160 - 40 * i)},
                           &r)),
           top + Eigen::Vector3f(0.6f, 0.05f, z), static_cast<float>(r.Uniform(-0.15, 0.15)));
    z += thickness;
  }
  // A chair pushed under the desk: its seat is under the top, its back in front of the edge.
  b->Add("chair", "desk chair", ChairMesh(Jitter({60, 60, 70}, &r)),
         centre + Eigen::Vector3f(static_cast<float>(r.Uniform(-0.2, 0.2)), -0.25f, 0.f), kPi);
}

// A kitchen: a counter along the back wall with a sink, a microwave and bottles, a
// refrigerator and an oven beside it, a dining table with two cups side by side and chairs.
Eigen::Vector3d AddKitchen(SceneBuilder* b, TriangleMesh* structure) {
  Random& r = b->random();
  const float counter_top = 0.9f;
  structure->AddBox({0.9f, 3.85f, 0.f}, {3.7f, 4.45f, counter_top}, Jitter({200, 40, 40}, &r));
  const Rgb steel = Jitter({180, 180, 185}, &r), white = Jitter({235, 235, 230}, &r);
  b->Add("refrigerator", "refrigerator",
         ApplianceMesh(0.7f, 0.65f, 1.8f, white, Jitter({210, 210, 205}, &r)), {0.5f, 4.1f, 0.f},
         0.f);
  b->Add("oven", "oven", ApplianceMesh(0.6f, 0.6f, 0.9f, Jitter({60, 60, 60}, &r), {20, 20, 25}),
         {4.05f, 4.1f, 0.f}, 0.f);
  b->Add("sink", "sink", SinkMesh(steel), {1.8f, 4.15f, counter_top}, 0.f);
  b->Add("microwave", "microwave", ApplianceMesh(0.5f, 0.38f, 0.3f, white, {30, 30, 35}),
         {3.1f, 4.15f, counter_top}, static_cast<float>(r.Uniform(-0.1, 0.1)));
  b->Add("bottle", "bottle 1", BottleMesh(Jitter({40, 120, 60}, &r)), {2.35f, 4.05f, counter_top},
         0.f);
  b->Add("bottle", "bottle 2", BottleMesh(Jitter({120, 60, 30}, &r)), {2.47f, 4.1f, counter_top},
         0.f);
  const Eigen::Vector3f table(2.3f + static_cast<float>(r.Uniform(-0.2, 0.2)), 2.3f, 0.f);
  b->Add("dining table", "kitchen table", TableMesh(1.2f, 0.8f, 0.75f, Jitter({170, 130, 90}, &r)),
         table, 0.f);
  const Eigen::Vector3f top = table + Eigen::Vector3f(0.f, 0.f, 0.75f);
  b->Add("cup", "left cup", CupMesh(Jitter({230, 230, 225}, &r)),
         top + Eigen::Vector3f(-0.2f, 0.f, 0.f), 0.3f);
  b->Add("cup", "right cup", CupMesh(Jitter({40, 80, 180}, &r)),
         top + Eigen::Vector3f(-0.06f, 0.05f, 0.f), 2.8f);
  b->Add("chair", "chair left", ChairMesh(Jitter({110, 80, 50}, &r)),
         table + Eigen::Vector3f(-0.3f, -0.65f, 0.f), kPi);
  b->Add("chair", "chair right", ChairMesh(Jitter({110, 80, 50}, &r)),
         table + Eigen::Vector3f(0.35f, 0.65f, 0.f), 0.f);
  return Eigen::Vector3d(2.3, 3.2, 0.85);
}

// A lab: two benches with laptops, a monitor with keyboard and mouse, bottles and books, and
// chairs.
Eigen::Vector3d AddLab(SceneBuilder* b) {
  Random& r = b->random();
  const Rgb grey = Jitter({190, 190, 185}, &r), black = Jitter({40, 40, 45}, &r);
  const Rgb screen = Jitter({30, 60, 120}, &r);
  const Eigen::Vector3f back(2.5f, 3.7f, 0.f), front(2.5f, 2.3f, 0.f);
  b->Add("dining table", "back bench", TableMesh(2.0f, 0.7f, 0.9f, grey), back, 0.f);
  b->Add("dining table", "front bench", TableMesh(1.6f, 0.7f, 0.9f, grey), front, 0.f);
  const Eigen::Vector3f back_top = back + Eigen::Vector3f(0.f, 0.f, 0.9f);
  const Eigen::Vector3f front_top = front + Eigen::Vector3f(0.f, 0.f, 0.9f);
  // Two laptops side by side on the back bench, a monitor with its keyboard and mouse.
  b->Add("laptop", "laptop 1", LaptopMesh(Jitter({150, 150, 155}, &r), screen),
         back_top + Eigen::Vector3f(-0.7f, 0.f, 0.f), 0.1f);
  b->Add("laptop", "laptop 2", LaptopMesh(Jitter({90, 90, 95}, &r), screen),
         back_top + Eigen::Vector3f(-0.3f, 0.f, 0.f), -0.1f);
  b->Add("tv", "monitor", MonitorMesh(0.55f, 0.33f, black, screen),
         back_top + Eigen::Vector3f(0.45f, 0.15f, 0.f), 0.f);
  b->Add("keyboard", "keyboard", KeyboardMesh(black, Jitter({70, 70, 75}, &r)),
         back_top + Eigen::Vector3f(0.42f, -0.18f, 0.f), 0.05f);
  b->Add("mouse", "mouse", MouseMesh(black), back_top + Eigen::Vector3f(0.75f, -0.18f, 0.f), 0.f);
  // Bottles and a stack of two books on the front bench.
  for (int i = 0; i < 3; ++i) {
    b->Add("bottle", "bottle " + std::to_string(i + 1),
           BottleMesh(Jitter({60, static_cast<std::uint8_t>(110 + 30 * i), 160}, &r)),
           front_top + Eigen::Vector3f(-0.5f + 0.12f * i, 0.1f, 0.f), 0.f);
  }
  b->Add("book", "book 1", BookMesh(0.26f, 0.19f, 0.03f, Jitter({160, 60, 40}, &r)),
         front_top + Eigen::Vector3f(0.4f, 0.f, 0.f), 0.1f);
  b->Add("book", "book 2", BookMesh(0.23f, 0.17f, 0.025f, Jitter({40, 60, 160}, &r)),
         front_top + Eigen::Vector3f(0.4f, 0.f, 0.03f), -0.1f);
  b->Add("chair", "chair 1", ChairMesh(Jitter({50, 50, 60}, &r)),
         back + Eigen::Vector3f(-0.5f, -0.6f, 0.f), kPi + 0.2f);
  b->Add("chair", "chair 2", ChairMesh(Jitter({50, 50, 60}, &r)),
         back + Eigen::Vector3f(0.45f, -0.65f, 0.f), kPi - 0.3f);
  b->Add("chair", "chair 3", ChairMesh(Jitter({50, 50, 60}, &r)),
         front + Eigen::Vector3f(0.2f, -0.6f, 0.f), kPi);
  return Eigen::Vector3d(2.5, 3.0, 0.9);
}

// A stable hash of a name (std::hash differs between standard libraries).
std::uint64_t NameHash(const std::string& name) {
  std::uint64_t hash = 14695981039346656037ull;
  for (char c : name) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return hash;
}

// A camera sweeping an arc in front of `target`, looking at it from about 1.5 m high.
std::vector<Eigen::Isometry3d> Sweep(const Eigen::Vector3d& target, double radius, int frames,
                                     Random* random) {
  std::vector<Eigen::Isometry3d> poses;
  const double start = random->Uniform(-1.1, -0.9), end = random->Uniform(0.9, 1.1);
  for (int i = 0; i < frames; ++i) {
    const double s = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.5;
    const double angle = start + (end - start) * s;  // around +z, 0: straight in front (-y)
    const Eigen::Vector3d eye =
        target + Eigen::Vector3d(radius * std::sin(angle), -radius * std::cos(angle),
                                 0.65 + 0.15 * std::sin(3.0 * s * M_PI));
    poses.push_back(testing::LookAt(eye, target));
  }
  return poses;
}

}  // namespace

Rgb Texture::Sample(const Eigen::Vector2f& uv) const {
  if (width <= 0 || height <= 0) return Rgb{0, 0, 0};
  const float u = uv.x() - std::floor(uv.x()), v = uv.y() - std::floor(uv.y());
  const int x = std::clamp(static_cast<int>(u * width), 0, width - 1);
  const int y = std::clamp(static_cast<int>((1.f - v) * height), 0, height - 1);
  return texels[static_cast<std::size_t>(y) * width + x];
}

const Texture* TriangleMesh::TextureOf(std::size_t t) const {
  if (t >= texture_of.size() || texture_of[t] < 0) return nullptr;
  return textures[static_cast<std::size_t>(texture_of[t])].get();
}

void TriangleMesh::PadTextures() {
  if (texture_of.empty()) return;
  texture_of.resize(triangles.size(), -1);
  corner_uvs.resize(triangles.size(),
                    {Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()});
}

void TriangleMesh::AddBox(const Eigen::Vector3f& min, const Eigen::Vector3f& max, const Rgb& color,
                          const Eigen::Isometry3f& T) {
  const int base = static_cast<int>(vertices.size());
  for (int i = 0; i < 8; ++i) {
    vertices.push_back(T * Eigen::Vector3f((i & 1) ? max.x() : min.x(), (i & 2) ? max.y() : min.y(),
                                           (i & 4) ? max.z() : min.z()));
  }
  // Faces wound counter-clockwise seen from outside.
  static const int kFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : kFaces) {
    triangles.emplace_back(base + f[0], base + f[1], base + f[2]);
    triangles.emplace_back(base + f[0], base + f[2], base + f[3]);
    colors.push_back(color);
    colors.push_back(color);
  }
  PadTextures();
}

void TriangleMesh::AddCylinder(const Eigen::Vector3f& base_centre, float radius, float height,
                               int sides, const Rgb& color) {
  const int base = static_cast<int>(vertices.size());
  for (int i = 0; i < sides; ++i) {
    const float a = 2.f * kPi * i / sides;
    const Eigen::Vector3f offset(radius * std::cos(a), radius * std::sin(a), 0.f);
    vertices.push_back(base_centre + offset);
    vertices.push_back(base_centre + offset + Eigen::Vector3f(0.f, 0.f, height));
  }
  vertices.push_back(base_centre);
  vertices.push_back(base_centre + Eigen::Vector3f(0.f, 0.f, height));
  const int bottom = base + 2 * sides, top = bottom + 1;
  for (int i = 0; i < sides; ++i) {
    const int j = (i + 1) % sides;
    const int b0 = base + 2 * i, t0 = b0 + 1, b1 = base + 2 * j, t1 = b1 + 1;
    triangles.emplace_back(b0, b1, t1);
    triangles.emplace_back(b0, t1, t0);
    triangles.emplace_back(bottom, b1, b0);
    triangles.emplace_back(top, t0, t1);
    for (int k = 0; k < 4; ++k) colors.push_back(color);
  }
  PadTextures();
}

void TriangleMesh::Append(const TriangleMesh& other, const Eigen::Isometry3f& T) {
  const int base = static_cast<int>(vertices.size());
  for (const Eigen::Vector3f& v : other.vertices) vertices.push_back(T * v);
  for (const Eigen::Vector3i& t : other.triangles) {
    triangles.push_back(t + Eigen::Vector3i::Constant(base));
  }
  colors.insert(colors.end(), other.colors.begin(), other.colors.end());
  if (other.texture_of.empty()) {
    PadTextures();
    return;
  }
  // Untextured triangles so far get "no texture", then other's entries with its textures.
  texture_of.resize(triangles.size() - other.triangles.size(), -1);
  corner_uvs.resize(texture_of.size(),
                    {Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero(), Eigen::Vector2f::Zero()});
  const int offset = static_cast<int>(textures.size());
  textures.insert(textures.end(), other.textures.begin(), other.textures.end());
  for (int index : other.texture_of) texture_of.push_back(index < 0 ? -1 : index + offset);
  corner_uvs.insert(corner_uvs.end(), other.corner_uvs.begin(), other.corner_uvs.end());
}

std::vector<Eigen::Vector3f> TriangleMesh::SampleSurface(std::size_t count,
                                                         std::uint64_t seed) const {
  std::vector<double> cumulative;
  double total = 0.0;
  for (const Eigen::Vector3i& t : triangles) {
    total += 0.5 * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
    cumulative.push_back(total);
  }
  std::vector<Eigen::Vector3f> samples;
  if (triangles.empty() || total <= 0.0) return samples;
  Random random(seed, 0x5A3F1E);
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = random.Uniform() * total;
    const std::size_t k = static_cast<std::size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    const Eigen::Vector3i& t = triangles[std::min(k, triangles.size() - 1)];
    double u = random.Uniform(), v = random.Uniform();
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    samples.push_back(vertices[t[0]] + static_cast<float>(u) * (vertices[t[1]] - vertices[t[0]]) +
                      static_cast<float>(v) * (vertices[t[2]] - vertices[t[0]]));
  }
  return samples;
}

void TriangleMesh::Bounds(Eigen::Vector3f* min, Eigen::Vector3f* max) const {
  *min = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  *max = Eigen::Vector3f::Constant(std::numeric_limits<float>::lowest());
  for (const Eigen::Vector3f& v : vertices) {
    *min = min->cwiseMin(v);
    *max = max->cwiseMax(v);
  }
}

std::vector<std::string> SceneKinds() { return {"desk", "office", "kitchen", "lab"}; }

bool MakeScene(const std::string& kind, std::uint64_t seed, int frames, Scene* scene,
               std::string* why, const FurnitureCatalog* catalog) {
  const std::vector<std::string> kinds = SceneKinds();
  if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) {
    *why = "unknown scene kind '" + kind + "' (desk, office, kitchen, lab)";
    return false;
  }
  if (frames < 1) {
    *why = "a scene needs at least one frame";
    return false;
  }
  *scene = Scene{};
  scene->kind = kind;
  scene->seed = seed;
  scene->intrinsics = CameraIntrinsics{};  // 640x480, fx = fy = 585 (Kinect-like)
  scene->intrinsics.width = 640;
  scene->intrinsics.height = 480;
  scene->intrinsics.fx = scene->intrinsics.fy = 585.0;
  scene->intrinsics.cx = 320.0;
  scene->intrinsics.cy = 240.0;
  Random random(seed, NameHash(kind));
  SceneBuilder builder(scene, &random, catalog);
  const float w = 5.f, d = 4.5f, h = 2.7f;
  AddRoom(w, d, h, &random, &scene->structure);
  if (kind == "kitchen" || kind == "lab") {
    const Eigen::Vector3d target =
        kind == "kitchen" ? AddKitchen(&builder, &scene->structure) : AddLab(&builder);
    scene->trajectory = Sweep(target, 2.0, frames, &random);
    return true;
  }
  const Eigen::Vector3f desk(2.5f + static_cast<float>(random.Uniform(-0.2, 0.2)), 3.4f, 0.f);
  AddDesk(&builder, desk, /*two_monitors=*/kind == "office");
  if (kind == "office") {
    // A second chair standing free, a plant in the corner, a bookshelf's worth of structure.
    builder.Add("chair", "visitor chair", ChairMesh(Jitter({120, 40, 40}, &random)),
                Eigen::Vector3f(1.2f, 2.6f, 0.f), static_cast<float>(random.Uniform(0.3, 0.9)));
    builder.Add("potted plant", "plant", PottedPlantMesh(), Eigen::Vector3f(4.4f, 4.0f, 0.f), 0.f);
    scene->structure.AddBox({0.05f, 3.7f, 0.f}, {1.0f, 4.45f, 1.8f},
                            Jitter({140, 110, 80}, &random));
  }
  scene->trajectory = Sweep(Eigen::Vector3d(desk.x(), desk.y(), 0.8), 1.7, frames, &random);
  return true;
}

namespace {

bool Numbers(const nlohmann::json& value, std::size_t n, std::vector<float>* out) {
  if (!value.is_array() || value.size() != n) return false;
  out->clear();
  for (const nlohmann::json& v : value) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) return false;
    out->push_back(v.get<float>());
  }
  return true;
}

}  // namespace

bool MakeSceneFromFile(const std::string& path, const FurnitureCatalog* catalog, Scene* scene,
                       std::string* why) {
  std::ifstream in(path);
  const nlohmann::json file =
      in ? nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false) : nlohmann::json();
  if (!in || file.is_discarded() || !file.is_object()) {
    *why = path + ": cannot be read as a JSON object";
    return false;
  }
  std::vector<float> room, target;
  if (!Numbers(file.value("room", nlohmann::json()), 3, &room) || room[0] <= 0.f ||
      room[1] <= 0.f || room[2] <= 0.f) {
    *why = path + ": \"room\" must be [width, depth, height] in metres, all > 0";
    return false;
  }
  const nlohmann::json camera = file.value("camera", nlohmann::json::object());
  const int frames = camera.value("frames", 300);
  const double radius = camera.value("radius", 1.7);
  const nlohmann::json waypoints = camera.value("waypoints", nlohmann::json::array());
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> eye_target;  // of the waypoints
  for (std::size_t i = 0; i < waypoints.size(); ++i) {
    std::vector<float> eye, at;
    if (!waypoints[i].is_object() ||
        !Numbers(waypoints[i].value("eye", nlohmann::json()), 3, &eye) ||
        !Numbers(waypoints[i].value("target", nlohmann::json()), 3, &at)) {
      *why = path + ": camera.waypoints[" + std::to_string(i) +
             "] needs \"eye\" and \"target\" [x, y, z]";
      return false;
    }
    eye_target.emplace_back(Eigen::Vector3d(eye[0], eye[1], eye[2]),
                            Eigen::Vector3d(at[0], at[1], at[2]));
  }
  if ((eye_target.empty() && !Numbers(camera.value("target", nlohmann::json()), 3, &target)) ||
      frames < 1 || !(radius > 0.0)) {
    *why = path +
           ": \"camera\" needs \"target\" [x, y, z] (or \"waypoints\"), \"frames\" >= 1, "
           "\"radius\" > 0";
    return false;
  }
  *scene = Scene{};
  scene->kind = file.value("kind", std::string("custom"));
  scene->seed = file.value("seed", std::uint64_t{1});
  scene->intrinsics.width = 640;
  scene->intrinsics.height = 480;
  scene->intrinsics.fx = scene->intrinsics.fy = 585.0;
  scene->intrinsics.cx = 320.0;
  scene->intrinsics.cy = 240.0;
  Random random(scene->seed, NameHash(scene->kind));
  SceneBuilder builder(scene, &random, catalog);
  AddRoom(room[0], room[1], room[2], &random, &scene->structure);
  const nlohmann::json objects = file.value("objects", nlohmann::json::array());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = path + ": objects[" + std::to_string(i) + "]";
    const nlohmann::json& entry = objects[i];
    const std::string class_name = entry.value("class", std::string());
    std::vector<float> position, size;
    if (CocoClassId(class_name) < 0) {
      *why = where + ": class '" + class_name + "' is not a COCO class";
      return false;
    }
    if (!Numbers(entry.value("position", nlohmann::json()), 3, &position)) {
      *why = where + ": \"position\" must be [x, y, z] (the base centre, metres)";
      return false;
    }
    const bool has_size = entry.contains("size");
    if (has_size &&
        (!Numbers(entry["size"], 3, &size) || size[0] <= 0.f || size[1] <= 0.f || size[2] <= 0.f)) {
      *why = where + ": \"size\" must be [width, depth, height], all > 0";
      return false;
    }
    const std::string mesh_name = entry.value("mesh", std::string());
    // Without a size the catalog mesh keeps its own; the stand-in box then needs one.
    if (!has_size) {
      const std::vector<const FurnitureEntry*> found =
          catalog != nullptr ? catalog->Named({mesh_name}) : std::vector<const FurnitureEntry*>{};
      if (found.empty()) {
        *why = where + ": \"size\" is needed (no catalog mesh '" + mesh_name + "' to take it from)";
        return false;
      }
      size = {found[0]->size_m.x(), found[0]->size_m.y(), found[0]->size_m.z()};
    }
    TriangleMesh box;
    box.AddBox({-size[0] / 2, -size[1] / 2, 0.f}, {size[0] / 2, size[1] / 2, size[2]},
               Jitter({160, 160, 160}, &random));
    const std::vector<std::string> names = {mesh_name};
    builder.Add(class_name, entry.value("name", class_name + " " + std::to_string(i + 1)), box,
                Eigen::Vector3f(position[0], position[1], position[2]),
                entry.value("yaw_deg", 0.f) * kPi / 180.f, mesh_name.empty() ? nullptr : &names);
  }
  if (eye_target.empty()) {
    scene->trajectory =
        Sweep(Eigen::Vector3d(target[0], target[1], target[2]), radius, frames, &random);
    return true;
  }
  // Frames spread evenly over the waypoints, eye and target moving in straight lines between.
  for (int f = 0; f < frames; ++f) {
    const double t =
        frames == 1 ? 0.0 : static_cast<double>(f) * (eye_target.size() - 1) / (frames - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(t), eye_target.size() - 1);
    const std::size_t j = std::min(i + 1, eye_target.size() - 1);
    const double a = t - static_cast<double>(i);
    scene->trajectory.push_back(
        testing::LookAt((1.0 - a) * eye_target[i].first + a * eye_target[j].first,
                        (1.0 - a) * eye_target[i].second + a * eye_target[j].second));
  }
  return true;
}

}  // namespace objmap::sim
