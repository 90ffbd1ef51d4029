// The synthetic scene generator: determinism, the depth noise model on a known plane, the
// ground-truth detector, and a written sequence read back by the 7-Scenes reader.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <tuple>

#include "dataset/sequence_reader.h"
#include "detection/detections_file.h"
#include "evaluation/evaluation_io.h"
#include "sim/furniture_catalog.h"
#include "sim/renderer.h"
#include "sim/scene.h"
#include "sim/sequence_writer.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

namespace fs = std::filesystem;

// A wall facing the camera at `distance` metres: the camera looks along +z from the origin.
Scene WallScene(double distance) {
  Scene scene;
  scene.intrinsics.width = 640;
  scene.intrinsics.height = 480;
  scene.intrinsics.fx = scene.intrinsics.fy = 585.0;
  scene.intrinsics.cx = 320.0;
  scene.intrinsics.cy = 240.0;
  const float d = static_cast<float>(distance);
  scene.structure.AddBox({-5.f, -5.f, d}, {5.f, 5.f, d + 0.1f}, {200, 200, 200});
  scene.trajectory = {Eigen::Isometry3d::Identity()};
  return scene;
}

TEST(SimScene, TheSameSeedGivesTheSameFramesAndAnotherSeedAnotherScene) {
  Scene a, b, c;
  std::string why;
  ASSERT_TRUE(MakeScene("office", 7, 5, &a, &why)) << why;
  ASSERT_TRUE(MakeScene("office", 7, 5, &b, &why)) << why;
  ASSERT_TRUE(MakeScene("office", 8, 5, &c, &why)) << why;
  ASSERT_EQ(a.objects.size(), b.objects.size());
  const RenderedFrame fa = Render(a, a.trajectory[2], DepthNoiseConfig{}, a.seed, 2);
  const RenderedFrame fb = Render(b, b.trajectory[2], DepthNoiseConfig{}, b.seed, 2);
  EXPECT_EQ(fa.depth.depth_m, fb.depth.depth_m);
  EXPECT_EQ(fa.color.rgb, fb.color.rgb);
  EXPECT_EQ(fa.instance, fb.instance);
  // Another frame index draws other noise; another seed places the objects elsewhere.
  const RenderedFrame other = Render(a, a.trajectory[2], DepthNoiseConfig{}, a.seed, 3);
  EXPECT_NE(other.depth.depth_m, fa.depth.depth_m);
  EXPECT_FALSE(a.objects[0].T_W_O.isApprox(c.objects[0].T_W_O));
  EXPECT_FALSE(MakeScene("garage", 1, 5, &c, &why));
  EXPECT_NE(why.find("unknown scene kind 'garage'"), std::string::npos) << why;
}

TEST(SimScene, TheHardCasesAreInTheOffice) {
  Scene scene;
  std::string why;
  ASSERT_TRUE(MakeScene("office", 1, 2, &scene, &why)) << why;
  int tvs = 0, keyboards = 0, cups = 0, books = 0, chairs = 0;
  for (const SceneObject& object : scene.objects) {
    const std::string name(CocoClassName(object.class_id));
    tvs += name == "tv", keyboards += name == "keyboard", cups += name == "cup";
    books += name == "book", chairs += name == "chair";
  }
  EXPECT_EQ(tvs, 2);  // side by side
  EXPECT_EQ(keyboards, 1);
  EXPECT_EQ(cups, 2);    // close together
  EXPECT_EQ(books, 3);   // stacked
  EXPECT_GE(chairs, 1);  // one under the desk
}

TEST(SimScene, ThePapersFourKindsHoldTheirClasses) {
  const std::map<std::string, std::vector<std::string>> expected = {
      {"desk", {"dining table", "laptop", "keyboard", "mouse", "cup", "book", "chair"}},
      {"office", {"dining table", "tv", "keyboard", "cup", "book", "chair", "potted plant"}},
      {"kitchen", {"refrigerator", "oven", "sink", "microwave", "bottle", "cup", "chair"}},
      {"lab", {"dining table", "laptop", "tv", "keyboard", "bottle", "book", "chair"}}};
  for (const std::string& kind : SceneKinds()) {
    Scene scene;
    std::string why;
    ASSERT_TRUE(MakeScene(kind, 1, 10, &scene, &why)) << why;
    std::set<std::string> classes;
    for (const SceneObject& object : scene.objects)
      classes.insert(std::string(CocoClassName(object.class_id)));
    for (const std::string& name : expected.at(kind)) {
      EXPECT_EQ(classes.count(name), 1u) << kind << " lacks " << name;
    }
    // Every object is in view of some frame of the sweep.
    const RenderedFrame middle = Render(scene, scene.trajectory[5], DepthNoiseConfig{}, 1, 5);
    std::set<int> seen(middle.instance.begin(), middle.instance.end());
    EXPECT_GE(seen.size(), scene.objects.size() / 2) << kind;
  }
}

TEST(SimScene, AScenesFileGivesItsRoomObjectsAndCamera) {
  const fs::path dir =
      fs::temp_directory_path() / ("objmap_scene_file_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "scene.json").string();
  std::ofstream(path) << R"({"kind": "two cups", "seed": 9, "room": [4, 3, 2.5],
    "objects": [
      {"class": "dining table", "position": [2, 2, 0], "size": [1.2, 0.8, 0.75]},
      {"class": "cup", "name": "my mug", "position": [1.9, 2, 0.75], "size": [0.1, 0.08, 0.1],
       "yaw_deg": 90}],
    "camera": {"target": [2, 2, 0.8], "radius": 1.5, "frames": 4}})";
  Scene scene;
  std::string why;
  ASSERT_TRUE(MakeSceneFromFile(path, nullptr, &scene, &why)) << why;
  EXPECT_EQ(scene.kind, "two cups");
  EXPECT_EQ(scene.seed, 9u);
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.objects[1].class_id, CocoClassId("cup"));
  EXPECT_EQ(scene.objects[1].name, "my mug");
  EXPECT_TRUE(scene.objects[1].T_W_O.translation().isApprox(Eigen::Vector3d(1.9, 2, 0.75), 1e-6));
  Eigen::Vector3f min, max;
  scene.objects[0].mesh.Bounds(&min, &max);
  EXPECT_NEAR(max.z() - min.z(), 0.75f, 1e-5f);
  EXPECT_EQ(scene.trajectory.size(), 4u);
  // The camera looks at the target from inside the room.
  const Eigen::Vector3d eye = scene.trajectory[2].translation();
  EXPECT_TRUE(eye.x() > 0 && eye.x() < 4 && eye.y() > 0 && eye.y() < 3) << eye.transpose();

  std::ofstream(path) << R"({"room": [4, 3, 2.5], "camera": {"target": [2, 2, 0.8]},
    "objects": [{"class": "mug", "position": [1, 1, 0], "size": [0.1, 0.1, 0.1]}]})";
  EXPECT_FALSE(MakeSceneFromFile(path, nullptr, &scene, &why));
  EXPECT_NE(why.find("objects[0]: class 'mug' is not a COCO class"), std::string::npos) << why;
  std::ofstream(path) << R"({"room": [4, 3, 2.5], "camera": {"target": [2, 2, 0.8]},
    "objects": [{"class": "cup", "mesh": "Coffee mug", "position": [1, 1, 0]}]})";
  EXPECT_FALSE(MakeSceneFromFile(path, nullptr, &scene, &why));
  EXPECT_NE(why.find("\"size\" is needed"), std::string::npos) << why;

  // A trajectory through waypoints (read as float32): five frames over three waypoints, the
  // camera at each one and halfway between, looking at the target of the moment.
  std::ofstream(path) << R"({"room": [4, 3, 2.5], "camera": {"frames": 5, "waypoints": [
      {"eye": [1, 1, 1.5], "target": [2, 2, 0.8]}, {"eye": [3, 1, 1.5], "target": [2, 2, 0.8]},
      {"eye": [3, 2.5, 1.2], "target": [1, 2, 0.8]}]}})";
  ASSERT_TRUE(MakeSceneFromFile(path, nullptr, &scene, &why)) << why;
  ASSERT_EQ(scene.trajectory.size(), 5u);
  EXPECT_TRUE(scene.trajectory[0].translation().isApprox(Eigen::Vector3d(1, 1, 1.5), 1e-9));
  EXPECT_TRUE(scene.trajectory[1].translation().isApprox(Eigen::Vector3d(2, 1, 1.5), 1e-9));
  EXPECT_TRUE(scene.trajectory[4].translation().isApprox(Eigen::Vector3d(3, 2.5, 1.2), 1e-6));
  // Camera z (the optical axis) points at the target: halfway, (1.5, 2, 0.8) from (3, 1.75, 1.35).
  const Eigen::Vector3d axis = scene.trajectory[3].linear().col(2);
  const Eigen::Vector3d towards =
      (Eigen::Vector3d(1.5, 2, 0.8) - Eigen::Vector3d(3, 1.75, 1.35)).normalized();
  EXPECT_GT(axis.dot(towards), 0.9999);
  std::ofstream(path) << R"({"room": [4, 3, 2.5], "camera": {"waypoints": [{"eye": [1, 1, 1]}]}})";
  EXPECT_FALSE(MakeSceneFromFile(path, nullptr, &scene, &why));
  EXPECT_NE(why.find("camera.waypoints[0] needs \"eye\" and \"target\""), std::string::npos) << why;
  fs::remove_all(dir);
}

TEST(SimRenderer, APlaneAtAKnownDistanceReadsWithinTheNoiseModel) {
  const double distance = 2.0;
  const Scene scene = WallScene(distance);
  const DepthNoiseConfig noise;
  DepthNoiseConfig exact = noise;
  exact.enabled = false;
  const RenderedFrame clean = Render(scene, scene.trajectory[0], exact, 1, 0);
  EXPECT_NEAR(clean.depth.depth_m[240 * 640 + 320], distance, 1e-5);
  EXPECT_NEAR(clean.depth.depth_m[10 * 640 + 10], distance, 1e-5);  // depth is z, not range

  const RenderedFrame noisy = Render(scene, scene.trajectory[0], noise, 1, 0);
  const double sigma = noise.axial_a_m + noise.axial_b_per_m * (distance - noise.axial_z0_m) *
                                             (distance - noise.axial_z0_m);
  // Depths are fx * baseline / (k / subpixels) for whole k: about z^2 / (8 fx b) apart.
  const double fb = 585.0 * noise.baseline_m;
  const double step = distance * distance / (noise.disparity_subpixels * fb);
  double sum = 0.0, sum2 = 0.0;
  int n = 0, off_grid = 0;
  for (int v = 100; v < 380; ++v) {
    for (int u = 100; u < 540; ++u) {
      const double z = noisy.depth.depth_m[v * 640 + u];
      ASSERT_GT(z, 0.0);
      sum += z, sum2 += z * z, ++n;
      const double k = noise.disparity_subpixels * fb / z;
      if (std::abs(k - std::round(k)) > 1e-3) ++off_grid;
    }
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, distance, 0.002);
  // Gaussian axial noise plus the quantization's uniform error.
  const double expected_sd = std::sqrt(sigma * sigma + step * step / 12.0);
  EXPECT_GT(sd, 0.8 * expected_sd);
  EXPECT_LT(sd, 1.2 * expected_sd);
  EXPECT_EQ(off_grid, 0);
}

// A 2 x 2 texel texture (red, green / blue, white) on a 1 m square facing the camera: every
// pixel takes the texel under it, not one colour for the triangle, also across the diagonal
// that splits the square into its two triangles.
TEST(SimRenderer, TexturedTrianglesAreSampledPerPixel) {
  Scene scene = WallScene(2.0);
  scene.structure = TriangleMesh{};
  TriangleMesh& square = scene.structure;
  square.vertices = {
      {-0.5f, -0.5f, 2.f}, {0.5f, -0.5f, 2.f}, {0.5f, 0.5f, 2.f}, {-0.5f, 0.5f, 2.f}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  square.colors = {{0, 0, 0}, {0, 0, 0}};
  auto texture = std::make_shared<Texture>();
  texture->width = texture->height = 2;
  texture->texels = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {255, 255, 255}};  // top row first
  square.textures = {texture};
  square.texture_of = {0, 0};
  // Image y (and camera y) runs downwards, texture v upwards: camera y = -0.5 is the top.
  const Eigen::Vector2f uv0(0.f, 1.f), uv1(1.f, 1.f), uv2(1.f, 0.f), uv3(0.f, 0.f);
  square.corner_uvs = {{uv0, uv1, uv2}, {uv0, uv2, uv3}};
  DepthNoiseConfig exact;
  exact.enabled = false;
  const RenderedFrame frame = Render(scene, scene.trajectory[0], exact, 1, 0);
  // The square spans about 146 px around the centre (585 * 0.5 / 2).
  auto color_at = [&](int u, int v) {
    const std::size_t i = static_cast<std::size_t>(v) * 640 + u;
    return Rgb{frame.color.rgb[3 * i], frame.color.rgb[3 * i + 1], frame.color.rgb[3 * i + 2]};
  };
  auto dominant = [](const Rgb& c) {
    if (c[0] > 200 && c[1] > 200 && c[2] > 200) return std::string("white");
    if (c[0] > 200 && c[1] < 50 && c[2] < 50) return std::string("red");
    if (c[1] > 200 && c[0] < 50 && c[2] < 50) return std::string("green");
    if (c[2] > 200 && c[0] < 50 && c[1] < 50) return std::string("blue");
    return std::string("other");
  };
  // Quadrants sampled on both sides of the diagonal (u - 320 = v - 240).
  for (const auto& [du, dv] : {std::pair{-100, -40}, {-40, -100}}) {
    EXPECT_EQ(dominant(color_at(320 + du, 240 + dv)), "red") << du << "," << dv;
  }
  for (const auto& [du, dv] : {std::pair{100, 40}, {40, 100}}) {
    EXPECT_EQ(dominant(color_at(320 + du, 240 + dv)), "white") << du << "," << dv;
  }
  EXPECT_EQ(dominant(color_at(420, 160)), "green");
  EXPECT_EQ(dominant(color_at(220, 320)), "blue");
}

TEST(SimRenderer, GrazingSurfacesAndFarPixelsReadNothing) {
  Scene scene = WallScene(2.0);
  // Turn the wall by 85 degrees about the vertical axis: seen almost edge-on.
  Eigen::Isometry3f turn = Eigen::Isometry3f::Identity();
  turn.translate(Eigen::Vector3f(0.f, 0.f, 2.f));
  turn.rotate(Eigen::AngleAxisf(85.f * static_cast<float>(M_PI) / 180.f, Eigen::Vector3f::UnitY()));
  turn.translate(Eigen::Vector3f(0.f, 0.f, -2.f));
  TriangleMesh turned;
  turned.Append(scene.structure, turn);
  scene.structure = turned;
  const DepthNoiseConfig noise;
  const RenderedFrame frame = Render(scene, scene.trajectory[0], noise, 1, 0);
  // The wall's normal, and the angle each pixel's ray makes with it.
  const Eigen::Vector3f normal = turn.linear() * Eigen::Vector3f(0.f, 0.f, -1.f);
  const double cos_limit = std::cos(noise.max_incidence_deg * M_PI / 180.0);
  int grazing = 0, grazing_read = 0, steep_read = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * 640 + u;
      const float z = frame.true_depth_m[i];
      if (z <= 0.6f || z >= 4.4f) continue;  // inside the valid range
      const Eigen::Vector3f ray =
          Eigen::Vector3f((u - 320.f) / 585.f, (v - 240.f) / 585.f, 1.f).normalized();
      const double incidence = std::abs(normal.dot(ray));
      if (incidence < cos_limit - 0.01) {
        ++grazing;
        grazing_read += frame.depth.depth_m[i] > 0.f;
      } else if (incidence > cos_limit + 0.05) {
        steep_read += frame.depth.depth_m[i] > 0.f;
      }
    }
  }
  EXPECT_GT(grazing, 1000);
  EXPECT_EQ(grazing_read, 0);
  EXPECT_GT(steep_read, 1000);
  // Beyond 4.5 m nothing reads either.
  const Scene far = WallScene(6.0);
  const RenderedFrame far_frame = Render(far, far.trajectory[0], DepthNoiseConfig{}, 1, 0);
  EXPECT_EQ(far_frame.depth.depth_m[240 * 640 + 320], 0.f);
  EXPECT_NEAR(far_frame.true_depth_m[240 * 640 + 320], 6.0, 1e-5);
}

TEST(SimDetector, APerfectDetectorBoxesEveryVisibleObjectAndConfusionSwapsLookAlikes) {
  Scene scene;
  std::string why;
  ASSERT_TRUE(MakeScene("office", 3, 60, &scene, &why)) << why;
  const Eigen::Isometry3d& T_W_C = scene.trajectory[30];
  const RenderedFrame frame = Render(scene, T_W_C, DepthNoiseConfig{}, scene.seed, 30);
  DetectorNoiseConfig perfect;
  perfect.miss_probability = perfect.confusion_probability = 0.0;
  perfect.false_positives_per_frame = perfect.box_jitter = 0.0;
  perfect.small_object_px = perfect.min_visible_px;
  const std::vector<Detection> found =
      DetectFromInstances(scene, frame, T_W_C, perfect, scene.seed, 30);
  // Every object showing enough pixels, boxed exactly by its pixels.
  int visible = 0;
  for (const SceneObject& object : scene.objects) {
    int pixels = 0, u_min = 640;
    for (int i = 0; i < 640 * 480; ++i) {
      if (frame.instance[i] != object.id) continue;
      ++pixels;
      u_min = std::min(u_min, i % 640);
    }
    if (pixels < perfect.min_visible_px) continue;
    ++visible;
    const bool boxed = std::any_of(found.begin(), found.end(), [&](const Detection& d) {
      return d.class_id == object.class_id && d.box.x_min == static_cast<float>(u_min);
    });
    EXPECT_TRUE(boxed) << object.name;
  }
  EXPECT_EQ(static_cast<int>(found.size()), visible);
  EXPECT_GE(visible, 8);

  DetectorNoiseConfig confused = perfect;
  confused.confusion_probability = 1.0;
  for (const Detection& d : DetectFromInstances(scene, frame, T_W_C, confused, scene.seed, 30)) {
    EXPECT_NE(std::string(CocoClassName(d.class_id)), "tv");  // a tv is always called a laptop
  }
}

TEST(SimDrift, OdometryDriftGrowsAlongTheSweepAndVanishesWithoutErrors) {
  Scene scene;
  std::string why;
  ASSERT_TRUE(MakeScene("office", 1, 300, &scene, &why)) << why;
  const std::vector<Eigen::Isometry3d> drifted =
      DriftedTrajectory(scene.trajectory, DriftConfig{}, scene.seed);
  ASSERT_EQ(drifted.size(), scene.trajectory.size());
  EXPECT_TRUE(drifted.front().isApprox(scene.trajectory.front()));
  const Eigen::Isometry3d error = scene.trajectory.back().inverse() * drifted.back();
  // About 3.5 m travelled: several degrees and centimetres off at the end.
  EXPECT_GT(Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI, 3.0);
  EXPECT_GT((drifted.back().translation() - scene.trajectory.back().translation()).norm(), 0.05);
  DriftConfig none;
  none.yaw_bias_deg_per_m = none.yaw_noise_deg_per_m = none.scale_error = 0.0;
  const std::vector<Eigen::Isometry3d> exact = DriftedTrajectory(scene.trajectory, none, 1);
  for (std::size_t k = 0; k < exact.size(); k += 37) {
    EXPECT_TRUE(exact[k].isApprox(scene.trajectory[k], 1e-9)) << k;
  }
}

TEST(SimFurniture, CatalogMeshesLoadUprightAtTheirCatalogSize) {
  std::string why;
  const auto catalog = FurnitureCatalog::Open(FurnitureCatalog::kDefaultFolder, &why);
  if (!catalog) GTEST_SKIP() << "SKIPPED: needs " << why;
  EXPECT_GT(catalog->entries().size(), 500u);
  const std::vector<const FurnitureEntry*> mugs = catalog->Named({"Coffee mug"});
  ASSERT_FALSE(mugs.empty());
  TriangleMesh mug;
  ASSERT_TRUE(catalog->LoadMesh(*mugs[0], &mug, &why)) << why;
  EXPECT_GT(mug.triangles.size(), 100u);
  EXPECT_EQ(mug.colors.size(), mug.triangles.size());
  Eigen::Vector3f min, max;
  mug.Bounds(&min, &max);
  // Width along x, depth along y, height along z, standing on z = 0 and centred.
  const Eigen::Vector3f& size = mugs[0]->size_m;
  EXPECT_NEAR(max.x() - min.x(), size.x(), 1e-3f * size.x() + 1e-5f);
  EXPECT_NEAR(max.y() - min.y(), size.y(), 1e-3f * size.y() + 1e-5f);
  EXPECT_NEAR(max.z() - min.z(), size.z(), 1e-3f * size.z() + 1e-5f);
  EXPECT_NEAR(min.z(), 0.f, 1e-5f);
  EXPECT_NEAR(min.x() + max.x(), 0.f, 1e-4f);
  // A chair is taller than wide: its up axis became z.
  const std::vector<const FurnitureEntry*> chairs = catalog->Named({"Chair"});
  ASSERT_FALSE(chairs.empty());
  TriangleMesh chair;
  ASSERT_TRUE(catalog->LoadMesh(*chairs[0], &chair, &why)) << why;
  chair.Bounds(&min, &max);
  EXPECT_NEAR(max.z() - min.z(), chairs[0]->size_m.z(), 1e-3f);

  // A scene dressed with catalog meshes keeps the procedural objects' places and classes.
  Scene procedural, dressed;
  ASSERT_TRUE(MakeScene("office", 2, 3, &procedural, &why)) << why;
  ASSERT_TRUE(MakeScene("office", 2, 3, &dressed, &why, catalog.get())) << why;
  ASSERT_EQ(dressed.objects.size(), procedural.objects.size());
  int replaced = 0;
  for (std::size_t k = 0; k < dressed.objects.size(); ++k) {
    EXPECT_EQ(dressed.objects[k].class_id, procedural.objects[k].class_id);
    EXPECT_TRUE(dressed.objects[k].T_W_O.isApprox(procedural.objects[k].T_W_O));
    replaced +=
        dressed.objects[k].mesh.triangles.size() != procedural.objects[k].mesh.triangles.size();
  }
  EXPECT_GE(replaced, 8);  // all but the keyboard and the mouse, where a mesh loads
}

TEST(SimSequence, AWrittenSequenceReadsBackWithItsGroundTruthAndDetections) {
  Scene scene;
  std::string why;
  ASSERT_TRUE(MakeScene("desk", 5, 3, &scene, &why)) << why;
  const fs::path dir = fs::temp_directory_path() / ("objmap_sim_" + std::to_string(getpid()));
  fs::remove_all(dir);
  ASSERT_TRUE(WriteSequence(scene, SequenceOptions{}, dir.string(), &why)) << why;

  std::unique_ptr<SequenceReader> reader = OpenSequence(dir.string(), &why);
  ASSERT_TRUE(reader) << why;
  ASSERT_EQ(reader->size(), 3u);
  RgbdFrame frame;
  ASSERT_TRUE(reader->ReadFrame(1, &frame, &why)) << why;
  EXPECT_DOUBLE_EQ(frame.intrinsics.fx, 585.0);
  EXPECT_TRUE(frame.T_W_C.isApprox(scene.trajectory[1], 1e-9));
  const RenderedFrame rendered =
      Render(scene, scene.trajectory[1], DepthNoiseConfig{}, scene.seed, 1);
  for (std::size_t i = 0; i < rendered.depth.depth_m.size(); i += 997) {
    EXPECT_NEAR(frame.depth.depth_m[i], rendered.depth.depth_m[i], 0.0006) << i;  // mm rounding
  }

  std::vector<GroundTruthObject> truth;
  ASSERT_TRUE(ReadGroundTruth((dir / "ground_truth.json").string(), &truth, &why)) << why;
  ASSERT_EQ(truth.size(), scene.objects.size());
  // visible_frames: the frames showing at least the detector's min_visible_px pixels of it.
  std::map<int, int> shown;
  for (std::size_t f = 0; f < scene.trajectory.size(); ++f) {
    const RenderedFrame at_f =
        Render(scene, scene.trajectory[f], DepthNoiseConfig{}, scene.seed, static_cast<int>(f));
    std::map<int, int> pixels;
    for (std::uint16_t id : at_f.instance) ++pixels[id];
    for (const auto& [id, count] : pixels) {
      if (count >= DetectorNoiseConfig{}.min_visible_px) ++shown[id];
    }
  }
  int shown_somewhere = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_EQ(truth[k].visible_frames, shown[scene.objects[k].id]) << k;
    shown_somewhere += truth[k].visible_frames > 0;
  }
  EXPECT_GE(shown_somewhere, 3);
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_EQ(truth[k].class_id, scene.objects[k].class_id);
    EXPECT_EQ(truth[k].surface_W.size(), 2000u);
    EXPECT_GT(truth[k].size_m.minCoeff(), 0.0);
  }
  DetectionsByFrame detections;
  ASSERT_TRUE(ReadDetectionsFile((dir / "detections.json").string(), &detections, &why)) << why;
  EXPECT_GT(detections.size(), 0u);

  // The seen surface: one exact point per 1 cm voxel, and every pixel the sensor returned
  // (within 4 m) lies in one of its voxels, of the structure or of the objects as it is.
  SeenSurface seen;
  bool present = false;
  ASSERT_TRUE(ReadSeenSurface((dir / "ground_truth.json").string(), &seen, &present, &why)) << why;
  ASSERT_TRUE(present);
  ASSERT_GT(seen.structure_W.size(), 1000u);
  ASSERT_GT(seen.objects_W.size(), 100u);
  auto voxels_of = [](const std::vector<Eigen::Vector3f>& points) {
    std::set<std::tuple<int, int, int>> voxels;
    for (const Eigen::Vector3f& p : points) {
      voxels.emplace(std::floor(p.x() / 0.01), std::floor(p.y() / 0.01), std::floor(p.z() / 0.01));
    }
    return voxels;
  };
  const auto structure_voxels = voxels_of(seen.structure_W);
  const auto object_voxels = voxels_of(seen.objects_W);
  EXPECT_EQ(structure_voxels.size(), seen.structure_W.size());
  EXPECT_EQ(object_voxels.size(), seen.objects_W.size());
  const CameraIntrinsics& K = scene.intrinsics;
  const Eigen::Isometry3f T_W_C = scene.trajectory[1].cast<float>();
  int checked = 0;
  for (std::size_t i = 0; i < rendered.true_depth_m.size(); i += 101) {
    const float z = rendered.true_depth_m[i];
    if (rendered.depth.depth_m[i] <= 0.f || z > 4.f) continue;
    const int u = static_cast<int>(i % K.width), v = static_cast<int>(i / K.width);
    // As the writer computes it, so both land in the same voxel to the last bit.
    const Eigen::Vector3f p = T_W_C * Eigen::Vector3f(static_cast<float>((u - K.cx) / K.fx * z),
                                                      static_cast<float>((v - K.cy) / K.fy * z), z);
    const std::tuple<int, int, int> voxel(std::floor(p.x() / 0.01), std::floor(p.y() / 0.01),
                                          std::floor(p.z() / 0.01));
    EXPECT_EQ((rendered.instance[i] == 0 ? structure_voxels : object_voxels).count(voxel), 1u)
        << "pixel " << u << "," << v;
    ++checked;
  }
  EXPECT_GT(checked, 1000);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace objmap::sim
