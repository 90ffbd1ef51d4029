// Second sessions of the synthetic scenes: the configured changes, each where the second
// trajectory sees it, resting on a support and clear of the other objects; a second camera that
// starts elsewhere yet sees what the first saw; and changes.json written beside the sequence.
// Boxes, supports and visibility are computed here from the meshes, not with the generator's
// own helpers.
#include "sim/revisit.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "evaluation/evaluation_io.h"
#include "sim/furniture_catalog.h"
#include "sim/renderer.h"
#include "sim/scene.h"
#include "types/coco_classes.h"

namespace objmap::sim {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 60;

struct Box {
  Eigen::Vector3d min, max;
};

// The world box of every vertex of the object.
Box VertexBox(const SceneObject& object) {
  Box box{Eigen::Vector3d::Constant(1e30), Eigen::Vector3d::Constant(-1e30)};
  for (const Eigen::Vector3f& v : object.mesh.vertices) {
    const Eigen::Vector3d p = object.T_W_O * v.cast<double>();
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

// As ground_truth.json gives it: the centre of the mesh bounds, moved by T_W_O.
Eigen::Vector3d BoxCentre(const SceneObject& object) {
  Eigen::Vector3f min, max;
  object.mesh.Bounds(&min, &max);
  return object.T_W_O * (0.5f * (min + max)).cast<double>();
}

// Overlapping by more than 2 mm on every axis (touching, as a cup on a table, is no clash).
bool Intersect(const Box& a, const Box& b) {
  for (int axis = 0; axis < 3; ++axis) {
    if (a.min[axis] > b.max[axis] - 0.002 || b.min[axis] > a.max[axis] - 0.002) return false;
  }
  return true;
}

struct Support {
  std::string name;
  Eigen::Vector2d min_xy, max_xy;
  double z;
};

// The room's floor (5 x 4.5 m), the kitchen's counter (AddKitchen's structure) and the tops of
// the dining tables.
std::vector<Support> Supports(const Scene& scene) {
  std::vector<Support> supports = {{"floor", {0.0, 0.0}, {5.0, 4.5}, 0.0}};
  if (scene.kind == "kitchen") supports.push_back({"counter", {0.9, 3.85}, {3.7, 4.45}, 0.9});
  for (const SceneObject& object : scene.objects) {
    if (std::string(CocoClassName(object.class_id)) != "dining table") continue;
    const Box box = VertexBox(object);
    supports.push_back({object.name, box.min.head<2>(), box.max.head<2>(), box.max.z()});
  }
  return supports;
}

// The support the object rests on: its bottom within 2 cm of the support's height, its centre
// over it; -1 when none.
int SupportOf(const SceneObject& object, const std::vector<Support>& supports) {
  const Box box = VertexBox(object);
  const Eigen::Vector2d centre = BoxCentre(object).head<2>();
  for (std::size_t i = 0; i < supports.size(); ++i) {
    const Support& s = supports[i];
    if (std::abs(box.min.z() - s.z) <= 0.02 && (centre.array() >= s.min_xy.array()).all() &&
        (centre.array() <= s.max_xy.array()).all()) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

// The highest support under the object's centre, at or below its bottom: the table under a
// stack of books for the top book; -1 when none.
int SupportBelow(const SceneObject& object, const std::vector<Support>& supports) {
  const Box box = VertexBox(object);
  const Eigen::Vector2d centre = BoxCentre(object).head<2>();
  int best = -1;
  for (std::size_t i = 0; i < supports.size(); ++i) {
    const Support& s = supports[i];
    if (s.z <= box.min.z() + 0.02 && (centre.array() >= s.min_xy.array()).all() &&
        (centre.array() <= s.max_xy.array()).all() &&
        (best < 0 || s.z > supports[static_cast<std::size_t>(best)].z)) {
      best = static_cast<int>(i);
    }
  }
  return best;
}

// Frames whose camera has the point in front, inside the image and within 4 m.
int FramesSeeing(const Eigen::Vector3d& p_W, const Scene& scene) {
  const CameraIntrinsics& K = scene.intrinsics;
  int frames = 0;
  for (const Eigen::Isometry3d& T_W_C : scene.trajectory) {
    const Eigen::Vector3d p = T_W_C.inverse() * p_W;
    if (p.z() <= 0.0 || p.norm() > 4.0) continue;
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    frames += u >= 0 && u < K.width && v >= 0 && v < K.height;
  }
  return frames;
}

const SceneObject* Find(const Scene& scene, int id) {
  for (const SceneObject& object : scene.objects) {
    if (object.id == id) return &object;
  }
  return nullptr;
}

double AngleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

// The largest frame-to-frame translation (metres) and rotation (degrees) of a trajectory.
std::pair<double, double> LargestStep(const std::vector<Eigen::Isometry3d>& trajectory) {
  double metres = 0.0, degrees = 0.0;
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    metres =
        std::max(metres, (trajectory[k].translation() - trajectory[k - 1].translation()).norm());
    degrees = std::max(degrees, AngleDeg(trajectory[k], trajectory[k - 1]));
  }
  return {metres, degrees};
}

void CheckRevisit(const Scene& first, const Scene& second, const SceneChanges& changes) {
  ASSERT_EQ(changes.removed.size(), 3u);
  ASSERT_EQ(changes.moved.size(), 3u);
  ASSERT_EQ(changes.added.size(), 3u);
  EXPECT_EQ(second.objects.size(), first.objects.size());  // 3 gone, 3 new
  const std::vector<Support> first_supports = Supports(first);
  const std::vector<Support> supports = Supports(second);
  ASSERT_EQ(supports.size(), first_supports.size());  // no table changes
  std::set<int> changed;
  for (const ObjectChange& c : changes.removed) {
    const SceneObject* before = Find(first, c.id);
    ASSERT_NE(before, nullptr) << c.id;
    EXPECT_EQ(Find(second, c.id), nullptr) << c.name;
    EXPECT_LT((BoxCentre(*before) - c.from_W).norm(), 1e-6) << c.name;
    EXPECT_GE(FramesSeeing(c.from_W, second), 10) << c.name << " was out of view";
    changed.insert(c.id);
  }
  int other_support = 0;
  for (const ObjectChange& c : changes.moved) {
    const SceneObject *before = Find(first, c.id), *after = Find(second, c.id);
    ASSERT_TRUE(before != nullptr && after != nullptr) << c.id;
    EXPECT_EQ(after->class_id, before->class_id);
    EXPECT_LT((BoxCentre(*before) - c.from_W).norm(), 1e-6) << c.name;
    EXPECT_LT((BoxCentre(*after) - c.to_W).norm(), 1e-6) << c.name;
    EXPECT_GE((c.to_W - c.from_W).norm(), 0.5) << c.name;
    const int from = SupportBelow(*before, first_supports), to = SupportOf(*after, supports);
    EXPECT_GE(from, 0) << c.name << " stood on nothing";
    EXPECT_GE(to, 0) << c.name << " rests on nothing";
    EXPECT_EQ(c.other_support, from != to) << c.name;
    other_support += from != to;
    EXPECT_GE(FramesSeeing(c.from_W, second), 10) << c.name << " old place out of view";
    EXPECT_GE(FramesSeeing(c.to_W, second), 10) << c.name << " new place out of view";
    changed.insert(c.id);
  }
  // Every kind has a table (desk, kitchen table, benches) besides the floor.
  EXPECT_GE(other_support, 1) << "no move onto another support";
  int largest_first_id = 0;
  for (const SceneObject& object : first.objects)
    largest_first_id = std::max(largest_first_id, object.id);
  const std::set<std::string> addable = {"cup",    "book",  "bottle",
                                         "laptop", "chair", "potted plant"};
  for (const ObjectChange& c : changes.added) {
    const SceneObject* after = Find(second, c.id);
    ASSERT_NE(after, nullptr) << c.id;
    EXPECT_GT(c.id, largest_first_id);
    EXPECT_EQ(addable.count(std::string(CocoClassName(after->class_id))), 1u) << c.name;
    EXPECT_LT((BoxCentre(*after) - c.to_W).norm(), 1e-6) << c.name;
    EXPECT_GE(SupportOf(*after, supports), 0) << c.name << " rests on nothing";
    EXPECT_GE(FramesSeeing(c.to_W, second), 10) << c.name << " out of view";
    changed.insert(c.id);
  }
  EXPECT_EQ(changed.size(), 9u);  // nothing changed twice
  // Moved and added objects clash with no other object of the second session.
  for (const SceneObject& object : second.objects) {
    const bool is_new = std::any_of(changes.moved.begin(), changes.moved.end(),
                                    [&](const ObjectChange& c) { return c.id == object.id; }) ||
                        object.id > largest_first_id;
    if (!is_new) continue;
    for (const SceneObject& other : second.objects) {
      EXPECT_TRUE(other.id == object.id || !Intersect(VertexBox(object), VertexBox(other)))
          << object.name << " intersects " << other.name;
    }
  }
  // The others stay as they were, with their ids.
  for (const SceneObject& object : first.objects) {
    if (changed.count(object.id) > 0) continue;
    const SceneObject* after = Find(second, object.id);
    ASSERT_NE(after, nullptr) << object.name;
    EXPECT_EQ(after->class_id, object.class_id);
    EXPECT_EQ(after->name, object.name);
    EXPECT_TRUE(after->T_W_O.isApprox(object.T_W_O, 1e-12)) << object.name;
  }
}

void CheckTrajectory(const Scene& first, const Scene& second) {
  ASSERT_EQ(second.trajectory.size(), static_cast<std::size_t>(kFrames));
  const Eigen::Isometry3d& start = second.trajectory.front();
  for (const Eigen::Isometry3d* other : {&first.trajectory.front(), &first.trajectory.back()}) {
    EXPECT_TRUE((start.translation() - other->translation()).norm() >= 0.5 ||
                AngleDeg(start, *other) >= 30.0);
  }
  // Its first frame looks at what the first session saw: most of the surface it shows was in
  // view of the first session (inside an image, not hidden behind something nearer).
  DepthNoiseConfig exact;
  exact.enabled = false;
  const RenderedFrame start_frame = Render(second, start, exact, 0, 0);
  std::vector<RenderedFrame> first_frames;
  for (std::size_t k = 0; k < first.trajectory.size(); k += 4) {
    first_frames.push_back(Render(first, first.trajectory[k], exact, 0, static_cast<int>(k)));
  }
  const CameraIntrinsics& K = first.intrinsics;
  int surface = 0, seen_before = 0;
  for (int v = 4; v < K.height; v += 8) {
    for (int u = 4; u < K.width; u += 8) {
      const float z = start_frame.true_depth_m[static_cast<std::size_t>(v) * K.width + u];
      if (z <= 0.f) continue;
      const Eigen::Vector3d p_W =
          start * Eigen::Vector3d((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z);
      ++surface;
      for (std::size_t f = 0; f < first_frames.size(); ++f) {
        const Eigen::Vector3d p = first.trajectory[4 * f].inverse() * p_W;
        const int pu = static_cast<int>(std::lround(K.fx * p.x() / p.z() + K.cx));
        const int pv = static_cast<int>(std::lround(K.fy * p.y() / p.z() + K.cy));
        if (p.z() <= 0.0 || pu < 0 || pu >= K.width || pv < 0 || pv >= K.height) continue;
        const float there =
            first_frames[f].true_depth_m[static_cast<std::size_t>(pv) * K.width + pu];
        if (std::abs(there - p.z()) < 0.03) {
          ++seen_before;
          break;
        }
      }
    }
  }
  EXPECT_GT(seen_before, 0.7 * surface) << seen_before << " of " << surface;
  // As smooth as the first sweep, frame to frame.
  const auto [first_m, first_deg] = LargestStep(first.trajectory);
  const auto [second_m, second_deg] = LargestStep(second.trajectory);
  EXPECT_LE(second_m, 1.1 * first_m);
  EXPECT_LE(second_deg, 1.1 * first_deg);
}

void CheckKind(const std::string& kind, std::uint64_t seed, const FurnitureCatalog* catalog) {
  SCOPED_TRACE(kind + " seed " + std::to_string(seed) + (catalog ? " (catalog meshes)" : ""));
  Scene first, second;
  SceneChanges changes;
  std::string why;
  ASSERT_TRUE(MakeScene(kind, seed, kFrames, &first, &why, catalog)) << why;
  ASSERT_TRUE(
      MakeRevisit(first, RevisitConfig{}, seed + 1, kFrames, &second, &changes, &why, catalog))
      << why;
  EXPECT_EQ(changes.kind, kind);
  EXPECT_EQ(changes.scene_seed, seed);
  EXPECT_EQ(second.seed, seed + 1);
  CheckRevisit(first, second, changes);
  CheckTrajectory(first, second);
}

TEST(SimRevisit, EveryKindGetsItsChangesWhereTheSecondCameraSeesThem) {
  for (const std::string& kind : SceneKinds()) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) CheckKind(kind, seed, nullptr);
  }
}

// objmap_sim dresses scenes with the catalog's meshes when it is installed: other shapes and
// bounds to place and to see.
TEST(SimRevisit, EveryKindDressedWithCatalogMeshesGetsItsChanges) {
  std::string why;
  const auto catalog = FurnitureCatalog::Open(FurnitureCatalog::kDefaultFolder, &why);
  if (!catalog) GTEST_SKIP() << "SKIPPED: needs " << why;
  for (const std::string& kind : SceneKinds()) CheckKind(kind, 3, catalog.get());
}

TEST(SimRevisit, TheSameSeedGivesTheSameChangesAndBadRequestsAreRefused) {
  Scene first, a, b;
  SceneChanges changes_a, changes_b;
  std::string why;
  ASSERT_TRUE(MakeScene("lab", 3, kFrames, &first, &why)) << why;
  ASSERT_TRUE(MakeRevisit(first, RevisitConfig{}, 5, kFrames, &a, &changes_a, &why)) << why;
  ASSERT_TRUE(MakeRevisit(first, RevisitConfig{}, 5, kFrames, &b, &changes_b, &why)) << why;
  EXPECT_EQ(ChangesJson(changes_a), ChangesJson(changes_b));
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  EXPECT_TRUE(a.trajectory.back().isApprox(b.trajectory.back()));

  RevisitConfig negative;
  negative.moved = -1;
  EXPECT_FALSE(MakeRevisit(first, negative, 5, kFrames, &a, &changes_a, &why));
  EXPECT_NE(why.find("RevisitConfig"), std::string::npos) << why;
  RevisitConfig too_many;
  too_many.removed = 40;
  EXPECT_FALSE(MakeRevisit(first, too_many, 5, kFrames, &a, &changes_a, &why));
  EXPECT_NE(why.find("to remove"), std::string::npos) << why;
}

// A patrol drives the first path again, each pose within the configured drift of the first
// session's pose at the same point of the path, and still gets its changes where it sees them.
TEST(SimRevisit, APatrolDrivesTheFirstPathAgainALittleToOneSide) {
  for (const std::string& kind : SceneKinds()) {
    SCOPED_TRACE(kind);
    Scene first, second;
    SceneChanges changes;
    std::string why;
    ASSERT_TRUE(MakeScene(kind, 2, kFrames, &first, &why)) << why;
    RevisitConfig patrol;
    patrol.patrol = true;
    ASSERT_TRUE(MakeRevisit(first, patrol, 7, kFrames, &second, &changes, &why)) << why;
    ASSERT_EQ(second.trajectory.size(), first.trajectory.size());
    double largest_m = 0.0, largest_deg = 0.0;
    for (std::size_t i = 0; i < first.trajectory.size(); ++i) {
      const Eigen::Isometry3d relative = first.trajectory[i].inverse() * second.trajectory[i];
      largest_m = std::max(largest_m, relative.translation().norm());
      largest_deg =
          std::max(largest_deg, Eigen::AngleAxisd(relative.linear()).angle() * 180.0 / M_PI);
    }
    // Within the drift (3 cm on two axes and half of it on the third; 2 degrees and two halves).
    EXPECT_LE(largest_m, 1.6 * patrol.patrol_offset_m);
    EXPECT_GT(largest_m, 0.3 * patrol.patrol_offset_m);  // driven to one side, not replayed
    EXPECT_LE(largest_deg, 1.5 * patrol.patrol_offset_deg);
    EXPECT_EQ(changes.removed.size(), 3u);
    EXPECT_EQ(changes.added.size(), 3u);
  }
  RevisitConfig negative;
  negative.patrol = true;
  negative.patrol_offset_m = -0.1;
  Scene first, second;
  SceneChanges changes;
  std::string why;
  ASSERT_TRUE(MakeScene("desk", 2, kFrames, &first, &why)) << why;
  EXPECT_FALSE(MakeRevisit(first, negative, 7, kFrames, &second, &changes, &why));
  EXPECT_NE(why.find("patrol_offset_m"), std::string::npos) << why;
}

TEST(SimRevisit, TheSecondSessionIsWrittenWithItsChanges) {
  constexpr int kFewFrames = 25;
  Scene first, second;
  SceneChanges changes;
  std::string why;
  ASSERT_TRUE(MakeScene("desk", 4, kFewFrames, &first, &why)) << why;
  ASSERT_TRUE(MakeRevisit(first, RevisitConfig{}, 9, kFewFrames, &second, &changes, &why)) << why;
  const fs::path dir = fs::temp_directory_path() / ("objmap_revisit_" + std::to_string(getpid()));
  fs::remove_all(dir);
  ASSERT_TRUE(WriteRevisitSequence(second, changes, SequenceOptions{}, dir.string(), &why)) << why;
  EXPECT_TRUE(fs::exists(dir / "frame-000024.color.png"));

  std::ifstream in(dir / "changes.json");
  const nlohmann::json json = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded());
  EXPECT_EQ(json["format"], "objmap-changes-1");
  EXPECT_EQ(json["kind"], "desk");
  EXPECT_EQ(json["seed"], 4);
  EXPECT_EQ(json["revisit_seed"], 9);
  auto position = [](const nlohmann::json& p) {
    return Eigen::Vector3d(p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>());
  };
  ASSERT_EQ(json["removed"].size(), 3u);
  ASSERT_EQ(json["moved"].size(), 3u);
  ASSERT_EQ(json["added"].size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const nlohmann::json& removed = json["removed"][i];
    EXPECT_EQ(removed["id"], changes.removed[i].id);
    EXPECT_EQ(removed["class"], std::string(CocoClassName(changes.removed[i].class_id)));
    EXPECT_EQ(removed["name"], changes.removed[i].name);
    EXPECT_LT((position(removed["position"]) - changes.removed[i].from_W).norm(), 1e-9);
    const nlohmann::json& moved = json["moved"][i];
    EXPECT_EQ(moved["id"], changes.moved[i].id);
    EXPECT_LT((position(moved["from"]) - changes.moved[i].from_W).norm(), 1e-9);
    EXPECT_LT((position(moved["to"]) - changes.moved[i].to_W).norm(), 1e-9);
    EXPECT_EQ(moved["other_support"], changes.moved[i].other_support);
    const nlohmann::json& added = json["added"][i];
    EXPECT_EQ(added["id"], changes.added[i].id);
    EXPECT_LT((position(added["position"]) - changes.added[i].to_W).norm(), 1e-9);
  }

  // ground_truth.json holds the second session's objects, at the positions changes.json gives.
  std::vector<GroundTruthObject> truth;
  ASSERT_TRUE(ReadGroundTruth((dir / "ground_truth.json").string(), &truth, &why)) << why;
  ASSERT_EQ(truth.size(), second.objects.size());
  std::map<int, Eigen::Vector3d> centre_of;  // from the file: id -> its box's centre
  for (std::size_t k = 0; k < truth.size(); ++k) {
    EXPECT_EQ(truth[k].id, second.objects[k].id);
    EXPECT_EQ(truth[k].class_id, second.objects[k].class_id);
    centre_of[truth[k].id] = truth[k].T_W_B.translation();
  }
  for (const ObjectChange& c : changes.removed) EXPECT_EQ(centre_of.count(c.id), 0u);
  for (const ObjectChange& c : changes.moved) EXPECT_LT((centre_of[c.id] - c.to_W).norm(), 1e-9);
  for (const ObjectChange& c : changes.added) EXPECT_LT((centre_of[c.id] - c.to_W).norm(), 1e-9);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace objmap::sim
