// Matching, counts and model accuracy on hand-made cases, and the evaluation's file readers.
#include "evaluation/evaluation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "evaluation/evaluation_io.h"
#include "occupancy/occupancy_map.h"
#include "pointcloud_io/pointcloud_io.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

GroundTruthObject Real(int id, const char* name, const Eigen::Vector3d& centre,
                       const Eigen::Vector3d& size) {
  GroundTruthObject object;
  object.id = id;
  object.class_id = CocoClassId(name);
  object.T_W_B.translation() = centre;
  object.size_m = size;
  return object;
}

MappedObject Mapped(ObjectId id, const char* name, const Eigen::Vector3d& min_W,
                    const Eigen::Vector3d& max_W) {
  MappedObject object;
  object.id = id;
  object.class_id = CocoClassId(name);
  object.min_W = min_W;
  object.max_W = max_W;
  object.centroid_W = 0.5 * (min_W + max_W);
  return object;
}

const ClassCounts& Counts(const ObjectEvaluation& evaluation, const char* name) {
  return evaluation.per_class.at(CocoClassId(name));
}

// Every case the paper's table names: a duplicate, a merge of two monitors side by side, a miss,
// a wrong label, a plain false positive.
TEST(EvaluateObjects, CountsDuplicatesMergesMissesAndWrongLabels) {
  const Eigen::Vector3d cup_size(0.08, 0.08, 0.1), tv_size(1.0, 0.1, 0.6);
  const std::vector<GroundTruthObject> real = {
      Real(1, "cup", {0, 0, 0}, cup_size),
      Real(2, "cup", {0.5, 0, 0}, cup_size),
      Real(3, "tv", {2.0, 0, 1}, tv_size),
      Real(4, "tv", {3.05, 0, 1}, tv_size),
      Real(5, "chair", {5, 0, 0.45}, {0.5, 0.5, 0.9}),
  };
  const std::vector<MappedObject> mapped = {
      Mapped(11, "cup", {-0.04, -0.04, -0.05}, {0.04, 0.04, 0.05}),  // cup 1
      Mapped(12, "cup", {-0.03, -0.05, -0.04}, {0.05, 0.03, 0.04}),  // cup 1 again
      Mapped(13, "tv", {1.5, -0.05, 0.7}, {3.55, 0.05, 1.3}),        // both monitors
      Mapped(14, "couch", {4.75, -0.25, 0.0}, {5.25, 0.25, 0.9}),    // the chair, mislabelled
      Mapped(15, "cup", {9.9, 9.9, 9.9}, {10.1, 10.1, 10.1}),        // nothing there
  };
  const ObjectEvaluation evaluation = EvaluateObjects(real, mapped, EvaluationConfig{});

  const ClassCounts& cups = Counts(evaluation, "cup");
  EXPECT_EQ(cups.real, 2);
  EXPECT_EQ(cups.mapped, 3);
  EXPECT_EQ(cups.true_positives, 1);
  EXPECT_EQ(cups.duplicates, 1);
  EXPECT_EQ(cups.misses, 1);           // the second cup
  EXPECT_EQ(cups.false_positives, 1);  // the cup at (10, 10, 10)

  const ClassCounts& tvs = Counts(evaluation, "tv");
  EXPECT_EQ(tvs.true_positives, 1);
  EXPECT_EQ(tvs.merges, 1);
  EXPECT_EQ(tvs.misses, 1);
  EXPECT_EQ(tvs.false_positives, 0);

  EXPECT_EQ(Counts(evaluation, "chair").misses, 1);
  const ClassCounts& couches = Counts(evaluation, "couch");
  EXPECT_EQ(couches.false_positives, 1);
  EXPECT_EQ(couches.wrong_labels, 1);

  const ClassCounts& all = evaluation.totals;
  EXPECT_EQ(all.real, 5);
  EXPECT_EQ(all.mapped, 5);
  EXPECT_EQ(all.true_positives, 2);
  EXPECT_EQ(all.false_positives, 2);
  EXPECT_EQ(all.misses, 3);
  EXPECT_EQ(all.duplicates, 1);
  EXPECT_DOUBLE_EQ(all.Precision(), 2.0 / 5.0);
  EXPECT_DOUBLE_EQ(all.Recall(), 2.0 / 5.0);
  ASSERT_EQ(evaluation.matches.size(), 2u);
}

// An object the sequence never showed (a chair behind the camera's path) is not real: not a
// miss, not a true positive, counted apart as unseen; one shown in a single frame is real.
// Unknown objects have no class to be right or wrong about: they are counted apart, by whether
// they stand on a real object and whether the named objects missed that one.
TEST(EvaluateObjects, UnknownObjectsAreCountedApartFromTheClasses) {
  const Eigen::Vector3d cup_size(0.08, 0.08, 0.1);
  const std::vector<GroundTruthObject> real = {
      Real(1, "cup", {0, 0, 0}, cup_size),
      Real(2, "cup", {0.5, 0, 0}, cup_size),
  };
  MappedObject on_found = Mapped(11, "cup", {-0.04, -0.04, -0.05}, {0.04, 0.04, 0.05});
  on_found.class_id = kUnknownClassId;  // beside the named cup 1
  MappedObject on_missed = Mapped(12, "cup", {0.46, -0.04, -0.05}, {0.54, 0.04, 0.05});
  on_missed.class_id = kUnknownClassId;
  MappedObject on_nothing = Mapped(13, "cup", {5, 5, 5}, {5.1, 5.1, 5.1});
  on_nothing.class_id = kUnknownClassId;
  const std::vector<MappedObject> mapped = {
      Mapped(10, "cup", {-0.04, -0.04, -0.05}, {0.04, 0.04, 0.05}), on_found, on_missed,
      on_nothing};
  const ObjectEvaluation evaluation = EvaluateObjects(real, mapped, EvaluationConfig{});
  EXPECT_EQ(evaluation.per_class.count(kUnknownClassId), 0u);
  const ClassCounts& cups = Counts(evaluation, "cup");
  EXPECT_EQ(cups.mapped, 1);
  EXPECT_EQ(cups.true_positives, 1);
  EXPECT_EQ(cups.false_positives, 0);
  EXPECT_EQ(cups.duplicates, 0);
  EXPECT_EQ(cups.misses, 1);
  EXPECT_EQ(evaluation.unknown.mapped, 3);
  EXPECT_EQ(evaluation.unknown.on_real, 2);
  EXPECT_EQ(evaluation.unknown.on_missed, 1);
  EXPECT_EQ(evaluation.unknown.missed_marked, 1);
}

TEST(EvaluateObjects, ObjectsTheSequenceNeverShowedAreUnseenNotMissed) {
  std::vector<GroundTruthObject> real = {
      Real(1, "chair", {0, 0, 0.45}, {0.5, 0.5, 0.9}),
      Real(2, "chair", {3, 0, 0.45}, {0.5, 0.5, 0.9}),
      Real(3, "chair", {6, 0, 0.45}, {0.5, 0.5, 0.9}),
  };
  real[0].visible_frames = 0;   // never in view
  real[1].visible_frames = 1;   // in view once
  real[2].visible_frames = -1;  // not known: real, as before the field existed
  const std::vector<MappedObject> mapped = {
      Mapped(11, "chair", {2.75, -0.25, 0.0}, {3.25, 0.25, 0.9}),
  };
  const ObjectEvaluation evaluation = EvaluateObjects(real, mapped, EvaluationConfig{});
  const ClassCounts& chairs = Counts(evaluation, "chair");
  EXPECT_EQ(chairs.real, 2);
  EXPECT_EQ(chairs.unseen, 1);
  EXPECT_EQ(chairs.true_positives, 1);
  EXPECT_EQ(chairs.misses, 1);  // the one whose visibility is not known
  EXPECT_EQ(evaluation.totals.unseen, 1);
  EXPECT_DOUBLE_EQ(evaluation.totals.Recall(), 0.5);

  // A stricter evaluation asks for two frames: the chair seen once is unseen too, and the map's
  // chair standing on it becomes a false positive.
  EvaluationConfig two_frames;
  two_frames.min_visible_frames = 2;
  const ObjectEvaluation strict = EvaluateObjects(real, mapped, two_frames);
  EXPECT_EQ(Counts(strict, "chair").unseen, 2);
  EXPECT_EQ(Counts(strict, "chair").real, 1);
  EXPECT_EQ(Counts(strict, "chair").false_positives, 1);

  EvaluationConfig negative;
  negative.min_visible_frames = -1;
  std::string why;
  EXPECT_FALSE(negative.IsValid(&why));
  EXPECT_NE(why.find("min_visible_frames"), std::string::npos) << why;
}

// With models, a merge is a model lying substantially on two real objects: two mugs 2 cm apart,
// one model half on each is a merge; a model of one mug with a tenth of its points on the rim
// of the other is not, though its axis-aligned box holds most of both mugs' boxes.
TEST(EvaluateObjects, AModelOnTwoObjectsIsAMergeAModelWithAStrayRimIsNot) {
  const Eigen::Vector3d cup_size(0.08, 0.08, 0.1);
  const std::vector<GroundTruthObject> real = {Real(1, "cup", {0, 0, 0.05}, cup_size),
                                               Real(2, "cup", {0.1, 0, 0.05}, cup_size)};
  auto model_on = [](std::vector<std::pair<double, int>> centres_and_counts) {
    MappedObject object;
    object.class_id = CocoClassId("cup");
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo, sum = Eigen::Vector3d::Zero();
    for (const auto& [x, count] : centres_and_counts) {
      for (int i = 0; i < count; ++i) {
        const Eigen::Vector3d p(x + 0.03 * std::sin(i), 0.03 * std::cos(i), 0.01 + 0.0008 * i);
        object.model_W.push_back(p.cast<float>());
        lo = lo.cwiseMin(p), hi = hi.cwiseMax(p), sum += p;
      }
    }
    object.min_W = lo, object.max_W = hi;
    object.centroid_W = sum / static_cast<double>(object.model_W.size());
    return object;
  };
  MappedObject both = model_on({{0.0, 100}, {0.1, 100}});
  both.id = 1;
  EXPECT_EQ(Counts(EvaluateObjects(real, {both}, EvaluationConfig{}), "cup").merges, 1);
  MappedObject one_with_rim = model_on({{0.0, 90}, {0.1, 10}});
  one_with_rim.id = 2;
  ASSERT_GT(one_with_rim.max_W.x() - one_with_rim.min_W.x(), 0.15) << "its box spans both mugs";
  const ObjectEvaluation evaluation = EvaluateObjects(real, {one_with_rim}, EvaluationConfig{});
  EXPECT_EQ(Counts(evaluation, "cup").merges, 0);
  EXPECT_EQ(Counts(evaluation, "cup").true_positives, 1);

  // Mugs whose boxes overlap (handles): a model of one mug lies partly in the other's box too,
  // but only points in one box alone count, so it is no merge; a model of both still is.
  const std::vector<GroundTruthObject> overlapping = {Real(1, "cup", {0, 0, 0.05}, cup_size),
                                                      Real(2, "cup", {0.06, 0, 0.05}, cup_size)};
  MappedObject one = model_on({{0.0, 100}});
  one.id = 3;
  EXPECT_EQ(Counts(EvaluateObjects(overlapping, {one}, EvaluationConfig{}), "cup").merges, 0);
  MappedObject two = model_on({{-0.01, 100}, {0.07, 100}});
  two.id = 4;
  EXPECT_EQ(Counts(EvaluateObjects(overlapping, {two}, EvaluationConfig{}), "cup").merges, 1);
}

TEST(EvaluateObjects, APartlySeenObjectStillMatchesAndARotatedBoxIsHonoured) {
  // A table seen only at one end: its model's centroid is off centre but inside the real box.
  GroundTruthObject table = Real(1, "dining table", {0, 0, 0.7}, {2.0, 0.9, 0.05});
  // The same box turned by 90 degrees about z: 0.9 m along x, 2 m along y.
  table.T_W_B.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const MappedObject seen_end = Mapped(7, "dining table", {-0.4, 0.5, 0.68}, {0.4, 0.95, 0.72});
  ObjectEvaluation evaluation = EvaluateObjects({table}, {seen_end}, EvaluationConfig{});
  EXPECT_EQ(evaluation.totals.true_positives, 1);
  // Had the box not been turned, y = 0.725 would lie outside its 0.9 m width.
  table.T_W_B.linear().setIdentity();
  evaluation = EvaluateObjects({table}, {seen_end}, EvaluationConfig{});
  EXPECT_EQ(evaluation.totals.true_positives, 0);
  EXPECT_EQ(evaluation.totals.false_positives, 1);
}

TEST(EvaluateObjects, ModelAccuracyIsTheMeanDistanceToTheSurface) {
  GroundTruthObject book = Real(1, "book", {0, 0, 0}, {0.2, 0.2, 0.02});
  MappedObject mapped = Mapped(3, "book", {-0.1, -0.1, -0.01}, {0.1, 0.1, 0.01});
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) {
      book.surface_W.emplace_back(0.01f * i, 0.01f * j, 0.0f);
      mapped.model_W.emplace_back(0.01f * i, 0.01f * j, 0.003f);  // 3 mm above the surface
    }
  }
  const ObjectEvaluation evaluation = EvaluateObjects({book}, {mapped}, EvaluationConfig{});
  ASSERT_EQ(evaluation.matches.size(), 1u);
  EXPECT_NEAR(evaluation.matches[0].model_to_surface_m, 0.003, 1e-6);
  EXPECT_NEAR(evaluation.matches[0].surface_to_model_m, 0.003, 1e-6);
  EXPECT_NEAR(evaluation.mean_model_to_surface_m, 0.003, 1e-6);
  // A stray point 1 m away counts as the cap (10 cm), not as 1 m.
  MappedObject stray = mapped;
  stray.model_W.emplace_back(1.0f, 0.0f, 0.0f);
  const double n = static_cast<double>(stray.model_W.size());
  const ObjectEvaluation with_stray = EvaluateObjects({book}, {stray}, EvaluationConfig{});
  EXPECT_NEAR(with_stray.matches[0].model_to_surface_m, (0.003 * (n - 1) + 0.1) / n, 1e-6);
}

TEST(EvaluateObjects, WithAMeshModelAccuracyIsTheExactDistanceToItNotToTheSamples) {
  // A 2 m x 1 m table top (two triangles at z = 0.7) with 2000-like sparse samples: 10 cm apart.
  GroundTruthObject table = Real(1, "dining table", {1.0, 0.5, 0.7}, {2.0, 1.0, 0.02});
  table.mesh_vertices_W = {{0, 0, 0.7f}, {2, 0, 0.7f}, {2, 1, 0.7f}, {0, 1, 0.7f}};
  table.mesh_triangles = {{0, 1, 2}, {0, 2, 3}};
  for (int i = 0; i <= 20; ++i) {
    for (int j = 0; j <= 10; ++j) table.surface_W.emplace_back(0.1f * i, 0.1f * j, 0.7f);
  }
  MappedObject mapped = Mapped(2, "dining table", {0.2, 0.2, 0.69}, {1.8, 0.8, 0.71});
  // Model points 4 mm above the top, off the sample grid: 4 mm from the surface, but about 5 cm
  // from the nearest sample.
  for (int i = 0; i < 30; ++i) {
    for (int j = 0; j < 12; ++j)
      mapped.model_W.emplace_back(0.25f + 0.05f * i, 0.25f + 0.05f * j, 0.704f);
  }
  // Points beside the table's edge (x < 0) are as far as the edge, and one point 1 m below is
  // capped at 10 cm.
  mapped.model_W.emplace_back(-0.03f, 0.5f, 0.7f);
  mapped.model_W.emplace_back(1.0f, 0.5f, -0.3f);
  const double n = static_cast<double>(mapped.model_W.size());
  const ObjectEvaluation evaluation = EvaluateObjects({table}, {mapped}, EvaluationConfig{});
  ASSERT_EQ(evaluation.matches.size(), 1u);
  EXPECT_NEAR(evaluation.matches[0].model_to_surface_m, (0.004 * (n - 2) + 0.03 + 0.1) / n, 1e-5);

  GroundTruthObject samples_only = table;
  samples_only.mesh_triangles.clear();
  const ObjectEvaluation by_samples = EvaluateObjects({samples_only}, {mapped}, EvaluationConfig{});
  EXPECT_GT(by_samples.matches[0].model_to_surface_m, 0.02) << "the samples' spacing shows";
}

TEST(ScoreCounts, CountsInsideTheRangeAreRightAndTheRestMissesOrFalsePositives) {
  const std::map<int, CountRange> expected = {
      {CocoClassId("chair"), {4, 6}}, {CocoClassId("tv"), {2, 2}}, {CocoClassId("sink"), {1, 1}}};
  const std::map<int, int> found = {{CocoClassId("chair"), 3},
                                    {CocoClassId("tv"), 2},
                                    {CocoClassId("sink"), 2},
                                    {CocoClassId("cup"), 1}};
  const std::map<int, ClassCounts> scores = ScoreCounts(expected, found);
  const ClassCounts& chairs = scores.at(CocoClassId("chair"));
  EXPECT_EQ(chairs.true_positives, 3);
  EXPECT_EQ(chairs.misses, 1);
  EXPECT_EQ(chairs.real, 4);
  EXPECT_EQ(scores.at(CocoClassId("tv")).true_positives, 2);
  EXPECT_EQ(scores.at(CocoClassId("sink")).true_positives, 1);
  EXPECT_EQ(scores.at(CocoClassId("sink")).false_positives, 1);
  EXPECT_EQ(scores.at(CocoClassId("cup")).false_positives, 1);
  EXPECT_EQ(scores.at(CocoClassId("cup")).real, 0);
}

// A 61 x 61 cm wall 2 m in front of a sensor at the origin (voxel centres at (k + 0.5) cm), its
// seen surface one point per voxel, and the cases each figure counts.
TEST(EvaluateOccupancy, CountsSurfaceOccupiedVoxelsMissedSurfaceAndSurfaceMappedFree) {
  OccupancyConfig config;
  config.resolution_m = 0.01;
  OccupancyMap map(config);
  ScanW wall;
  SeenSurface surface;
  for (int iy = -30; iy <= 30; ++iy) {
    for (int iz = -30; iz <= 30; ++iz) {
      const Eigen::Vector3f p(2.005f, 0.01f * iy + 0.005f, 0.01f * iz + 0.005f);
      wall.structure_points_W.push_back(p);
      surface.structure_W.push_back(p);
    }
  }
  map.Integrate(wall);
  OccupancyEvaluation result = EvaluateOccupancy(map, surface);
  EXPECT_EQ(result.occupied, 61u * 61u);
  EXPECT_DOUBLE_EQ(result.OccupiedPrecision(), 1.0);
  EXPECT_DOUBLE_EQ(result.StructureCompleteness(), 1.0);
  EXPECT_EQ(result.structure_free, 0u);

  // Five occupied voxels in the air, far from any surface.
  ScanW spurious;
  for (int k = 0; k < 5; ++k)
    spurious.structure_points_W.emplace_back(1.0025f, 0.5025f, 0.5025f + 0.01f * k);
  map.Integrate(spurious);
  // Seen but not mapped: five voxels of wall beyond the scanned part, and one voxel on a ray
  // to the wall (a pane the map carved through).
  for (int k = 0; k < 5; ++k) surface.structure_W.emplace_back(2.005f, 0.405f + 0.01f * k, 0.005f);
  surface.structure_W.emplace_back(1.0025f, 0.0025f, 0.0025f);
  // Object surface: one voxel in carved space (free: wrong), one behind the wall (unknown).
  surface.objects_W.emplace_back(1.5025f, 0.0025f, 0.0025f);
  surface.objects_W.emplace_back(2.5f, 0.0f, 0.0f);
  result = EvaluateOccupancy(map, surface);
  EXPECT_EQ(result.occupied, 61u * 61u + 5u);
  EXPECT_EQ(result.occupied_on_surface, 61u * 61u);
  EXPECT_EQ(result.occupied_near_surface, 61u * 61u);
  EXPECT_EQ(result.structure_surface, 61u * 61u + 6u);
  EXPECT_EQ(result.structure_occupied, 61u * 61u);
  EXPECT_EQ(result.structure_free, 1u);
  EXPECT_EQ(result.object_surface, 2u);
  EXPECT_EQ(result.object_free, 1u);
  EXPECT_DOUBLE_EQ(result.ObjectFreeShare(), 0.5);
  // A voxel two away from the surface is near it, not on it.
  ScanW beside;
  beside.structure_points_W.emplace_back(1.9825f, 0.0025f, 0.0025f);
  map.Integrate(beside);
  result = EvaluateOccupancy(map, surface);
  EXPECT_EQ(result.occupied_on_surface, 61u * 61u);
  EXPECT_EQ(result.occupied_near_surface, 61u * 61u + 1u);
}

class EvaluationFiles : public ::testing::Test {
 protected:
  EvaluationFiles()
      : dir_(fs::temp_directory_path() /
             ("objmap_evaluation_" + std::to_string(getpid()) + "_" +
              ::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "objects");
  }
  ~EvaluationFiles() override { fs::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};

TEST_F(EvaluationFiles, GroundTruthIsReadAndBadEntriesAreNamed) {
  const std::string path = Write("gt.json", R"({"objects": [{"id": 4, "class": "cup",
        "pose": [1,0,0,0.5, 0,1,0,0, 0,0,1,0.7, 0,0,0,1], "size": [0.08, 0.08, 0.1],
        "surface_sample": [[0.5, 0, 0.75], [0.46, 0, 0.7]]}]})");
  std::vector<GroundTruthObject> objects;
  std::string why;
  ASSERT_TRUE(ReadGroundTruth(path, &objects, &why)) << why;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].id, 4);
  EXPECT_EQ(objects[0].class_id, CocoClassId("cup"));
  EXPECT_DOUBLE_EQ(objects[0].T_W_B.translation().z(), 0.7);
  EXPECT_EQ(objects[0].surface_W.size(), 2u);
  EXPECT_EQ(objects[0].visible_frames, -1);  // not in the file: not known

  const std::string shown = Write("shown.json", R"({"objects": [{"id": 1, "class": "cup",
        "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1], "visible_frames": 0}]})");
  ASSERT_TRUE(ReadGroundTruth(shown, &objects, &why)) << why;
  EXPECT_EQ(objects[0].visible_frames, 0);
  const std::string bad_frames = Write("bad_frames.json", R"({"objects": [{"id": 1,
        "class": "cup", "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1],
        "visible_frames": -3}]})");
  EXPECT_FALSE(ReadGroundTruth(bad_frames, &objects, &why));
  EXPECT_NE(why.find("\"visible_frames\" must be an integer >= 0"), std::string::npos) << why;

  const std::string mug = Write("mug.json", R"({"objects": [{"id": 1, "class": "mug",
        "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1]}]})");
  EXPECT_FALSE(ReadGroundTruth(mug, &objects, &why));
  EXPECT_NE(why.find("objects[0]: class 'mug' is not a COCO class"), std::string::npos) << why;
  const std::string sheared = Write("sheared.json", R"({"objects": [{"id": 1, "class": "cup",
        "pose": [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1]}]})");
  EXPECT_FALSE(ReadGroundTruth(sheared, &objects, &why));
  EXPECT_NE(why.find("objects[0]: pose: "), std::string::npos) << why;
  const std::string no_size = Write("no_size.json", R"({"objects": [{"id": 1, "class": "cup",
        "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]})");
  EXPECT_FALSE(ReadGroundTruth(no_size, &objects, &why));
  EXPECT_NE(why.find("\"size\""), std::string::npos) << why;
  const std::string mesh = Write("mesh.json", R"({"objects": [{"id": 1, "class": "cup",
        "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1],
        "surface_mesh": {"vertices": [[0,0,0], [1,0,0], [0,1,0]], "triangles": [[0, 1, 2]]}}]})");
  ASSERT_TRUE(ReadGroundTruth(mesh, &objects, &why)) << why;
  EXPECT_EQ(objects[0].mesh_vertices_W.size(), 3u);
  ASSERT_EQ(objects[0].mesh_triangles.size(), 1u);
  EXPECT_EQ(objects[0].mesh_triangles[0], Eigen::Vector3i(0, 1, 2));
  const std::string bad_mesh = Write("bad_mesh.json", R"({"objects": [{"id": 1, "class": "cup",
        "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1], "size": [1, 1, 1],
        "surface_mesh": {"vertices": [[0,0,0], [1,0,0]], "triangles": [[0, 1, 2]]}}]})");
  EXPECT_FALSE(ReadGroundTruth(bad_mesh, &objects, &why));
  EXPECT_NE(why.find("surface_mesh triangle 0 is not 3 indices"), std::string::npos) << why;
  EXPECT_FALSE(ReadGroundTruth(Write("broken.json", "{\"objects\": ["), &objects, &why));
  EXPECT_NE(why.find("not valid JSON"), std::string::npos) << why;
}

TEST_F(EvaluationFiles, TheSeenSurfaceIsReadFromThePlyFilesTheGroundTruthNames) {
  std::string why;
  ASSERT_TRUE(WritePly((dir_ / "s.ply").string(), {{0.f, 0.f, 0.f}, {0.01f, 0.f, 0.f}}, {}, &why));
  ASSERT_TRUE(WritePly((dir_ / "o.ply").string(), {{1.f, 0.f, 0.f}}, {}, &why));
  SeenSurface surface;
  bool present = false;
  ASSERT_TRUE(ReadSeenSurface(Write("gt.json", R"({"objects": [], "seen_surface":
        {"voxel_size_m": 0.01, "structure": "s.ply", "objects": "o.ply"}})"),
                              &surface, &present, &why))
      << why;
  EXPECT_TRUE(present);
  EXPECT_DOUBLE_EQ(surface.voxel_size_m, 0.01);
  EXPECT_EQ(surface.structure_W.size(), 2u);
  EXPECT_EQ(surface.objects_W.size(), 1u);

  ASSERT_TRUE(ReadSeenSurface(Write("none.json", R"({"objects": []})"), &surface, &present, &why));
  EXPECT_FALSE(present);
  EXPECT_FALSE(ReadSeenSurface(Write("missing.json", R"({"seen_surface":
        {"voxel_size_m": 0.01, "structure": "gone.ply", "objects": "o.ply"}})"),
                               &surface, &present, &why));
  EXPECT_NE(why.find("seen_surface: "), std::string::npos) << why;
  EXPECT_NE(why.find("gone.ply"), std::string::npos) << why;
  EXPECT_FALSE(ReadSeenSurface(Write("bad.json", R"({"seen_surface": {"structure": "s.ply"}})"),
                               &surface, &present, &why));
  EXPECT_NE(why.find("voxel_size_m"), std::string::npos) << why;
}

TEST_F(EvaluationFiles, ExpectedCountsTakeNumbersAndRanges) {
  std::map<int, CountRange> counts;
  std::string why;
  ASSERT_TRUE(ReadExpectedCounts(Write("c.json", R"({"chair": [4, 6], "tv": 2})"), &counts, &why))
      << why;
  EXPECT_EQ(counts.at(CocoClassId("chair")).min, 4);
  EXPECT_EQ(counts.at(CocoClassId("chair")).max, 6);
  EXPECT_EQ(counts.at(CocoClassId("tv")).max, 2);
  EXPECT_FALSE(ReadExpectedCounts(Write("d.json", R"({"chair": [6, 4]})"), &counts, &why));
  EXPECT_NE(why.find("chair: expected a count >= 0 or a range [min, max]"), std::string::npos)
      << why;
  EXPECT_FALSE(ReadExpectedCounts(Write("e.json", R"({"monitor": 1})"), &counts, &why));
  EXPECT_NE(why.find("'monitor' is not a COCO class"), std::string::npos) << why;
}

TEST_F(EvaluationFiles, MapDirectoriesOfBothWritersGiveTheirInventoryObjectsWithModels) {
  std::string why;
  ASSERT_TRUE(WritePly((dir_ / "objects" / "1_cup.ply").string(),
                       {{0.f, 0.f, 0.f}, {0.01f, 0.f, 0.f}}, {{1, 2, 3}, {4, 5, 6}}, &why))
      << why;
  // `objmap map --out`: "in_inventory", bbox_min / bbox_max, models in objects/.
  Write("objects.json", R"({"objects": [
    {"id": 1, "class": "cup", "in_inventory": true, "centroid": [0.005, 0, 0],
     "bbox_min": [0, 0, 0], "bbox_max": [0.01, 0, 0]},
    {"id": 2, "class": "chair", "in_inventory": false, "centroid": [1, 1, 1],
     "bbox_min": [1, 1, 1], "bbox_max": [1, 1, 1]},
    {"id": 3, "class": "unknown", "in_inventory": true, "centroid": [2, 2, 2],
     "bbox_min": [2, 2, 2], "bbox_max": [2, 2, 2]}]})");
  std::vector<MappedObject> objects;
  ASSERT_TRUE(ReadMapDirectory(dir_.string(), &objects, &why)) << why;
  ASSERT_EQ(objects.size(), 2u);  // the chair is not in the inventory
  EXPECT_EQ(objects[0].class_id, CocoClassId("cup"));
  EXPECT_EQ(objects[1].class_id, kUnknownClassId);
  EXPECT_EQ(objects[0].model_W.size(), 2u);
  EXPECT_FLOAT_EQ(objects[0].model_W[1].x(), 0.01f);

  // `objmap export --objects`: "confirmed", "bounds", the PLY named by "ply".
  Write("objects.json", R"({"map_version": 3, "objects": [
    {"id": 1, "class": "cup", "confirmed": true, "centroid": [0.005, 0, 0],
     "bounds": {"min": [0, 0, 0], "max": [0.01, 0, 0]}, "ply": "objects/1_cup.ply"}]})");
  ASSERT_TRUE(ReadMapDirectory(dir_.string(), &objects, &why)) << why;
  ASSERT_EQ(objects.size(), 1u);
  EXPECT_EQ(objects[0].model_W.size(), 2u);

  Write("objects.json", R"({"objects": [{"id": 1, "class": "cup", "in_inventory": true}]})");
  EXPECT_FALSE(ReadMapDirectory(dir_.string(), &objects, &why));
  EXPECT_NE(why.find("objects[0]: centroid and bounds"), std::string::npos) << why;
  std::ofstream(dir_ / "objects" / "1_cup.ply") << "ply\nformat ascii 1.0\nend_header\n";
  Write("objects.json", R"({"objects": [
    {"id": 1, "class": "cup", "in_inventory": true, "centroid": [0, 0, 0],
     "bbox_min": [0, 0, 0], "bbox_max": [0, 0, 0]}]})");
  EXPECT_FALSE(ReadMapDirectory(dir_.string(), &objects, &why));
  EXPECT_NE(why.find("1_cup.ply: not a binary little-endian PLY"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
