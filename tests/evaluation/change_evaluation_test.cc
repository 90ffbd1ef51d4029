// Change detection between two sessions scored on hand-made cases: matching per kind and class,
// the distance that grows with the object, one-to-one matching, kept ids, the session filter,
// and the readers of both change files.
#include "evaluation/change_evaluation.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "evaluation/evaluation_io.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

GroundTruthChange Real(ChangeKind kind, int id, const char* name, const Eigen::Vector3d& place,
                       const Eigen::Vector3d& from = Eigen::Vector3d::Zero()) {
  GroundTruthChange change;
  change.kind = kind;
  change.id = id;
  change.class_id = CocoClassId(name);
  change.position_W = place;
  change.from_W = from;
  return change;
}

ReportedChange Report(ChangeKind kind, ObjectId id, const char* name, const Eigen::Vector3d& place,
                      const Eigen::Vector3d& from = Eigen::Vector3d::Zero(),
                      std::int64_t session_id = 2) {
  ReportedChange change;
  change.kind = kind;
  change.object_id = id;
  change.class_id = ObjectClassId(name);
  change.session_id = session_id;
  change.position_W = place;
  change.from_W = from;
  return change;
}

MappedObject Present(ObjectId id) {
  MappedObject object;
  object.id = id;
  return object;
}

// A cup taken away, a chair moved 2 m, a book put down.
const Eigen::Vector3d kCupWas(1, 0, 0.8), kChairFrom(3, 0, 0.45), kChairTo(5, 0, 0.45),
    kBookAt(0, 2, 0.75);

std::vector<GroundTruthChange> RealChanges() {
  return {Real(ChangeKind::kRemoved, 4, "cup", kCupWas),
          Real(ChangeKind::kMoved, 7, "chair", kChairTo, kChairFrom),
          Real(ChangeKind::kAdded, 21, "book", kBookAt)};
}

// What a perfect map reports: each change a few centimetres off, the chair under one id.
std::vector<ReportedChange> PerfectReports() {
  const Eigen::Vector3d off(0.03, -0.02, 0.01);
  return {Report(ChangeKind::kRemoved, 12, "cup", kCupWas + off),
          Report(ChangeKind::kMoved, 15, "chair", kChairTo - off, kChairFrom + off),
          Report(ChangeKind::kAdded, 30, "book", kBookAt + off)};
}

const std::vector<MappedObject> kPresent = {Present(15), Present(30)};

TEST(EvaluateChanges, PerfectReportScoresOne) {
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), PerfectReports(), &kPresent, ChangeEvaluationConfig{});
  for (ChangeKind kind : kChangeKinds) {
    EXPECT_EQ(e.Of(kind).real, 1) << ChangeKindName(kind);
    EXPECT_EQ(e.Of(kind).true_positives, 1) << ChangeKindName(kind);
    EXPECT_DOUBLE_EQ(e.Of(kind).Precision(), 1.0) << ChangeKindName(kind);
    EXPECT_DOUBLE_EQ(e.Of(kind).Recall(), 1.0) << ChangeKindName(kind);
  }
  EXPECT_EQ(e.totals.true_positives, 3);
  EXPECT_DOUBLE_EQ(e.totals.Precision(), 1.0);
  EXPECT_DOUBLE_EQ(e.totals.Recall(), 1.0);
  EXPECT_EQ(e.moved_kept_id, 1);
  EXPECT_EQ(e.moved_total, 1);
  ASSERT_EQ(e.matches.size(), 3u);
  EXPECT_EQ(e.matches[1].real_id, 7);
  EXPECT_EQ(e.matches[1].object_id, 15);
}

TEST(EvaluateChanges, MissingRemovalLowersRecall) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports.erase(reports.begin());  // the cup's removal
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &kPresent, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).misses, 1);
  EXPECT_DOUBLE_EQ(e.Of(ChangeKind::kRemoved).Recall(), 0.0);
  EXPECT_DOUBLE_EQ(e.totals.Recall(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(e.totals.Precision(), 1.0);
}

TEST(EvaluateChanges, SpuriousAdditionLowersPrecision) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports.push_back(Report(ChangeKind::kAdded, 31, "book", {4, 4, 0.75}));
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &kPresent, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kAdded).reported, 2);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).false_positives, 1);
  EXPECT_DOUBLE_EQ(e.Of(ChangeKind::kAdded).Precision(), 0.5);
  EXPECT_DOUBLE_EQ(e.Of(ChangeKind::kAdded).Recall(), 1.0);
  EXPECT_DOUBLE_EQ(e.totals.Precision(), 0.75);
}

TEST(EvaluateChanges, MoveReportedAsRemovalAndAdditionIsAMissAndNotKept) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports[1] = Report(ChangeKind::kRemoved, 15, "chair", kChairFrom);
  reports.push_back(Report(ChangeKind::kAdded, 40, "chair", kChairTo));
  const std::vector<MappedObject> present = {Present(40), Present(30)};
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &present, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kMoved).misses, 1);
  EXPECT_EQ(e.Of(ChangeKind::kMoved).true_positives, 0);
  EXPECT_EQ(e.moved_kept_id, 0);
  EXPECT_EQ(e.moved_total, 1);
  EXPECT_EQ(e.moved_as_removed_and_added, 1);
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).false_positives, 1);  // the chair's "removal"
  EXPECT_EQ(e.Of(ChangeKind::kAdded).false_positives, 1);    // the chair's "addition"
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).true_positives, 1);   // the cup still counts
}

TEST(EvaluateChanges, MoveUnderAnIdTheMapNoLongerHoldsIsMatchedButNotKept) {
  const std::vector<MappedObject> present = {Present(99), Present(30)};
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), PerfectReports(), &present, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kMoved).true_positives, 1);
  EXPECT_EQ(e.moved_kept_id, 0);
  // Without the map's objects there is nothing to check the id against.
  EXPECT_EQ(EvaluateChanges(RealChanges(), PerfectReports(), nullptr, ChangeEvaluationConfig{})
                .moved_kept_id,
            1);
}

TEST(EvaluateChanges, MoveNeedsBothPlaces) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports[1].from_W = kChairFrom + Eigen::Vector3d(1.0, 0, 0);  // right place now, wrong before
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &kPresent, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kMoved).misses, 1);
  EXPECT_EQ(e.Of(ChangeKind::kMoved).false_positives, 1);
}

TEST(EvaluateChanges, ClassMismatchDoesNotMatch) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports[2].class_id = CocoClassId("cup");  // the book, called a cup
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &kPresent, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kAdded).true_positives, 0);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).misses, 1);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).false_positives, 1);
}

TEST(EvaluateChanges, KindMismatchDoesNotMatch) {
  std::vector<ReportedChange> reports = PerfectReports();
  reports[2].kind = ChangeKind::kRemoved;  // the book's arrival, reported as a departure
  const ChangeEvaluation e =
      EvaluateChanges(RealChanges(), reports, &kPresent, ChangeEvaluationConfig{});
  EXPECT_EQ(e.Of(ChangeKind::kAdded).misses, 1);
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).false_positives, 1);
}

TEST(EvaluateChanges, SinceSessionLeavesEarlierReportsOut) {
  std::vector<ReportedChange> reports = PerfectReports();
  // Session 1 built the first map: a spurious addition there is not a change between sessions.
  reports.push_back(Report(ChangeKind::kAdded, 2, "tv", {0, 0, 1}, Eigen::Vector3d::Zero(),
                           /*session_id=*/1));
  ChangeEvaluationConfig config;
  EXPECT_EQ(EvaluateChanges(RealChanges(), reports, &kPresent, config)
                .Of(ChangeKind::kAdded)
                .false_positives,
            1);
  config.min_session_id = 2;
  const ChangeEvaluation e = EvaluateChanges(RealChanges(), reports, &kPresent, config);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).reported, 1);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).false_positives, 0);
  config.min_session_id = 3;  // nothing reported since
  EXPECT_DOUBLE_EQ(EvaluateChanges(RealChanges(), reports, &kPresent, config).totals.Recall(), 0.0);
  // Reports of a map that knew no sessions count when every session does.
  for (ReportedChange& report : reports) report.session_id = -1;
  config.min_session_id = 0;
  EXPECT_EQ(EvaluateChanges(RealChanges(), reports, &kPresent, config).totals.true_positives, 3);
}

TEST(EvaluateChanges, DistanceGrowsWithTheObject) {
  // 0.4 m off: too far for a cup (the 0.25 m floor), near enough for a 1.6 m table.
  const Eigen::Vector3d off(0.4, 0, 0);
  std::vector<GroundTruthChange> real = {Real(ChangeKind::kAdded, 1, "cup", {0, 0, 0}),
                                         Real(ChangeKind::kAdded, 2, "dining table", {5, 0, 0})};
  const std::vector<ReportedChange> reports = {
      Report(ChangeKind::kAdded, 10, "cup", Eigen::Vector3d(0, 0, 0) + off),
      Report(ChangeKind::kAdded, 11, "dining table", Eigen::Vector3d(5, 0, 0) + off)};
  EXPECT_EQ(EvaluateChanges(real, reports, nullptr, {}).totals.true_positives, 0);
  GroundTruthObject cup, table;
  cup.id = 1, cup.size_m = {0.08, 0.08, 0.1};
  table.id = 2, table.size_m = {1.6, 0.9, 0.75};
  EXPECT_TRUE(AttachGroundTruthSizes({}, {cup, table}, &real).empty());
  EXPECT_DOUBLE_EQ(real[1].largest_size_m, 1.6);
  const ChangeEvaluation e = EvaluateChanges(real, reports, nullptr, {});
  EXPECT_EQ(e.totals.true_positives, 1);
  ASSERT_EQ(e.matches.size(), 1u);
  EXPECT_EQ(e.matches[0].real_id, 2);
}

TEST(EvaluateChanges, OneReportMatchesOneChangeNearestFirst) {
  // Two cups put down 0.2 m apart, three reports: the one right on the second cup takes it, the
  // one between them (nearer the second) gets the first, the one far away none.
  const std::vector<GroundTruthChange> real = {Real(ChangeKind::kAdded, 1, "cup", {0, 0, 0}),
                                               Real(ChangeKind::kAdded, 2, "cup", {0.2, 0, 0})};
  const std::vector<ReportedChange> reports = {Report(ChangeKind::kAdded, 10, "cup", {0.12, 0, 0}),
                                               Report(ChangeKind::kAdded, 11, "cup", {0.21, 0, 0}),
                                               Report(ChangeKind::kAdded, 12, "cup", {3, 0, 0})};
  const ChangeEvaluation e = EvaluateChanges(real, reports, nullptr, {});
  EXPECT_EQ(e.totals.true_positives, 2);
  EXPECT_EQ(e.totals.false_positives, 1);
  ASSERT_EQ(e.matches.size(), 2u);
  EXPECT_EQ(e.matches[0].object_id, 10);
  EXPECT_EQ(e.matches[1].object_id, 11);
}

TEST(EvaluateChanges, UnseenAndUnknownAreCountedApart) {
  std::vector<GroundTruthChange> real = RealChanges();
  real[2].visible_frames = 0;  // the book was put where the second session never looked
  std::vector<ReportedChange> reports = PerfectReports();
  reports.erase(reports.begin() + 2);
  reports.push_back(Report(ChangeKind::kRemoved, 50, "unknown", {9, 9, 0}));
  const ChangeEvaluation e = EvaluateChanges(real, reports, &kPresent, {});
  EXPECT_EQ(e.Of(ChangeKind::kAdded).unseen, 1);
  EXPECT_EQ(e.Of(ChangeKind::kAdded).real, 0);
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).unknown_class, 1);
  EXPECT_EQ(e.Of(ChangeKind::kRemoved).false_positives, 0);
  EXPECT_DOUBLE_EQ(e.totals.Precision(), 1.0);
  EXPECT_DOUBLE_EQ(e.totals.Recall(), 1.0);
}

// Two mugs of one make: same class, same mesh, same size.
GroundTruthChange Mug(ChangeKind kind, int id, const Eigen::Vector3d& place,
                      const Eigen::Vector3d& from = Eigen::Vector3d::Zero()) {
  GroundTruthChange change = Real(kind, id, "cup", place, from);
  change.mesh_vertices = 812;
  change.mesh_triangles = 1620;
  change.size_m = {0.12, 0.09, 0.1};
  return change;
}

const Eigen::Vector3d kDesk(1, 0, 0.8), kShelf(4, 0, 1.2), kSink(0, 3, 0.9);

TEST(EvaluateChanges, ALookAlikeTakenAwayAndPutDownElsewhereReadsAsAMove) {
  // The ground truth: the mug on the desk taken away, a new one of the same make on the shelf.
  // The map saw one mug leave the desk and one arrive on the shelf: a move.
  const std::vector<GroundTruthChange> real = {Mug(ChangeKind::kRemoved, 4, kDesk),
                                               Mug(ChangeKind::kAdded, 9, kShelf)};
  const std::vector<ReportedChange> reports = {
      Report(ChangeKind::kMoved, 12, "cup", kShelf, kDesk)};
  const std::vector<MappedObject> present = {Present(12)};
  const ChangeEvaluation e = EvaluateChanges(real, reports, &present, {});
  EXPECT_EQ(e.lookalike_groups_reread, 1);
  EXPECT_EQ(e.totals.real, 1);
  EXPECT_EQ(e.totals.true_positives, 1);
  EXPECT_EQ(e.totals.false_positives, 0);
  EXPECT_EQ(e.moved_kept_id, 1);
  // Reported as seen (removed, added), the ground truth as written matches best, and stays.
  const std::vector<ReportedChange> as_seen = {Report(ChangeKind::kRemoved, 12, "cup", kDesk),
                                               Report(ChangeKind::kAdded, 30, "cup", kShelf)};
  const ChangeEvaluation seen = EvaluateChanges(real, as_seen, &present, {});
  EXPECT_EQ(seen.lookalike_groups_reread, 0);
  EXPECT_EQ(seen.totals.true_positives, 2);
  EXPECT_EQ(seen.totals.real, 2);
  // As written, the move matches nothing: a false move, a missed removal and addition.
  ChangeEvaluationConfig as_written;
  as_written.lookalikes_interchangeable = false;
  const ChangeEvaluation strict = EvaluateChanges(real, reports, &present, as_written);
  EXPECT_EQ(strict.lookalike_groups_reread, 0);
  EXPECT_EQ(strict.totals.true_positives, 0);
  EXPECT_EQ(strict.totals.false_positives, 1);
  EXPECT_EQ(strict.totals.misses, 2);
}

TEST(EvaluateChanges, WhichOfTwoIdenticalMugsMovedIsNotToBeSeen) {
  // The desk's mug went to the shelf and a new mug of the same make stands at the sink. A map
  // that has the desk's mug going to the sink and a new one on the shelf describes the same room.
  const std::vector<GroundTruthChange> real = {Mug(ChangeKind::kMoved, 4, kShelf, kDesk),
                                               Mug(ChangeKind::kAdded, 9, kSink)};
  const std::vector<ReportedChange> reports = {Report(ChangeKind::kMoved, 12, "cup", kSink, kDesk),
                                               Report(ChangeKind::kAdded, 30, "cup", kShelf)};
  const std::vector<MappedObject> present = {Present(12), Present(30)};
  const ChangeEvaluation e = EvaluateChanges(real, reports, &present, {});
  EXPECT_EQ(e.lookalike_groups_reread, 1);
  EXPECT_EQ(e.totals.true_positives, 2);
  EXPECT_EQ(e.totals.false_positives, 0);
  EXPECT_EQ(e.moved_kept_id, 1);
}

TEST(EvaluateChanges, AMoveIsNeverReadAsARemovalAndAnAddition) {
  // A moved mug reported as taken away and put down loses its identity whatever else there is:
  // no reading turns the real move into two changes to match the two reports.
  const std::vector<GroundTruthChange> real = {Mug(ChangeKind::kMoved, 4, kShelf, kDesk),
                                               Mug(ChangeKind::kAdded, 9, kSink)};
  const std::vector<ReportedChange> reports = {Report(ChangeKind::kRemoved, 12, "cup", kDesk),
                                               Report(ChangeKind::kAdded, 30, "cup", kShelf),
                                               Report(ChangeKind::kAdded, 31, "cup", kSink)};
  const ChangeEvaluation e = EvaluateChanges(real, reports, nullptr, {});
  EXPECT_EQ(e.Of(ChangeKind::kMoved).misses, 1);
  EXPECT_EQ(e.moved_as_removed_and_added, 1);
  EXPECT_EQ(e.totals.true_positives, 1);  // the sink's mug
}

TEST(EvaluateChanges, ObjectsThatDifferInSizeOrMeshAreNotLookAlikes) {
  GroundTruthChange desk_mug = Mug(ChangeKind::kRemoved, 4, kDesk);
  GroundTruthChange shelf_mug = Mug(ChangeKind::kAdded, 9, kShelf);
  EXPECT_TRUE(LookAlike(desk_mug, shelf_mug));
  shelf_mug.size_m.x() += 0.02;  // a larger mug of the same design
  EXPECT_FALSE(LookAlike(desk_mug, shelf_mug));
  const std::vector<ReportedChange> reports = {
      Report(ChangeKind::kMoved, 12, "cup", kShelf, kDesk)};
  EXPECT_EQ(EvaluateChanges({desk_mug, shelf_mug}, reports, nullptr, {}).totals.true_positives, 0);
  shelf_mug = Mug(ChangeKind::kAdded, 9, kShelf);
  shelf_mug.mesh_vertices = 640;  // another make
  EXPECT_FALSE(LookAlike(desk_mug, shelf_mug));
  desk_mug.mesh_vertices = shelf_mug.mesh_vertices = 0;  // no mesh given: nothing to compare
  EXPECT_FALSE(LookAlike(desk_mug, shelf_mug));
}

TEST(AttachGroundTruthSizes, GivesEachChangeItsMeshForTheLookAlikeTest) {
  std::vector<GroundTruthChange> real = {Real(ChangeKind::kRemoved, 4, "cup", kDesk),
                                         Real(ChangeKind::kAdded, 9, "cup", kShelf)};
  GroundTruthObject before_mug, after_mug;
  before_mug.id = 4;
  after_mug.id = 9;
  for (GroundTruthObject* mug : {&before_mug, &after_mug}) {
    mug->size_m = {0.12, 0.09, 0.1};
    mug->mesh_vertices_W.assign(3, Eigen::Vector3f::Zero());
    mug->mesh_triangles.assign(1, Eigen::Vector3i(0, 1, 2));
  }
  EXPECT_TRUE(AttachGroundTruthSizes({before_mug}, {after_mug}, &real).empty());
  EXPECT_EQ(real[0].mesh_vertices, 3);
  EXPECT_EQ(real[1].mesh_triangles, 1);
  EXPECT_TRUE(LookAlike(real[0], real[1]));
}

TEST(AttachGroundTruthSizes, NamesChangesMissingFromTheGivenFiles) {
  std::vector<GroundTruthChange> real = RealChanges();
  GroundTruthObject cup, chair_then, chair_now;
  cup.id = 4, cup.size_m = {0.08, 0.08, 0.1};
  chair_then.id = chair_now.id = 7;
  chair_then.size_m = chair_now.size_m = {0.5, 0.5, 0.9};
  chair_now.visible_frames = 12;
  // The second session's file lacks the book (21): the wrong file, most likely.
  EXPECT_EQ(AttachGroundTruthSizes({cup, chair_then}, {chair_now}, &real), std::vector<int>{21});
  EXPECT_DOUBLE_EQ(real[0].largest_size_m, 0.1);
  EXPECT_DOUBLE_EQ(real[1].largest_size_m, 0.9);
  EXPECT_EQ(real[1].visible_frames, 12);
  EXPECT_DOUBLE_EQ(real[2].largest_size_m, 0.0);
}

TEST(ChangeEvaluationConfig, RefusesBadValuesByName) {
  std::string why;
  EXPECT_TRUE(ChangeEvaluationConfig{}.IsValid(&why));
  ChangeEvaluationConfig config;
  config.min_match_distance_m = 0.0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("min_match_distance_m"), std::string::npos) << why;
  config = {};
  config.size_share = -0.5;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("size_share"), std::string::npos) << why;
  config = {};
  config.min_session_id = -1;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("min_session_id"), std::string::npos) << why;
}

class ChangeFiles : public ::testing::Test {
 protected:
  ChangeFiles()
      : dir_(fs::temp_directory_path() / ("objmap_changes_test_" + std::to_string(getpid()))) {
    fs::create_directories(dir_);
  }
  ~ChangeFiles() override { fs::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};

TEST_F(ChangeFiles, ReadsTheSimulatorsChanges) {
  const std::string path = Write("changes.json", R"({"format": "objmap-changes-1",
    "kind": "office", "seed": 3,
    "removed": [{"id": 4, "class": "cup", "name": "cup_1", "position": [1, 0, 0.8]}],
    "moved": [{"id": 7, "class": "chair", "name": "chair_2", "from": [3, 0, 0.45],
               "to": [5, 0, 0.45], "other_support": true}],
    "added": []})");
  std::vector<GroundTruthChange> changes;
  std::string why;
  ASSERT_TRUE(ReadGroundTruthChanges(path, &changes, &why)) << why;
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kRemoved);
  EXPECT_EQ(changes[0].class_id, CocoClassId("cup"));
  EXPECT_EQ(changes[1].kind, ChangeKind::kMoved);
  EXPECT_EQ(changes[1].id, 7);
  EXPECT_TRUE(changes[1].from_W.isApprox(Eigen::Vector3d(3, 0, 0.45)));
  EXPECT_TRUE(changes[1].position_W.isApprox(Eigen::Vector3d(5, 0, 0.45)));
}

TEST_F(ChangeFiles, ReadsTheMapsChanges) {
  const std::string path = Write("map_changes.json", R"({"format": "objmap-map-changes-1",
    "changes": [
      {"kind": "moved", "object_id": 12, "class": "chair", "session_id": 2, "keyframe_id": 57,
       "stamp": 12.3, "position": [5, 0, 0.45], "from": [3, 0, 0.45],
       "min": [4.75, -0.25, 0], "max": [5.25, 0.25, 0.9]},
      {"kind": "removed", "object_id": 3, "class": "unknown", "session_id": 3,
       "position": [1, 1, 1]}]})");
  std::vector<ReportedChange> changes;
  std::string why;
  ASSERT_TRUE(ReadReportedChanges(path, &changes, &why)) << why;
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].kind, ChangeKind::kMoved);
  EXPECT_EQ(changes[0].object_id, 12);
  EXPECT_EQ(changes[0].keyframe_id, 57);
  EXPECT_DOUBLE_EQ(changes[0].stamp, 12.3);
  EXPECT_TRUE(changes[0].from_W.isApprox(Eigen::Vector3d(3, 0, 0.45)));
  EXPECT_TRUE(changes[0].max_W.isApprox(Eigen::Vector3d(5.25, 0.25, 0.9)));
  EXPECT_EQ(changes[1].class_id, kUnknownClassId);
  EXPECT_EQ(changes[1].session_id, 3);
}

// Each malformed file is refused with the file, the entry and the field in the reason.
TEST_F(ChangeFiles, RefusesMalformedFilesNamingFileAndField) {
  struct Case {
    const char* text;
    const char* reason;
  };
  const std::vector<Case> simulator_cases = {
      {R"({"removed": []})", "\"format\" (\"objmap-changes-1\") is missing"},
      {R"({"format": "objmap-map-changes-1", "changes": []})",
       "\"format\" is 'objmap-map-changes-1', expected 'objmap-changes-1'"},
      {R"({"format": "objmap-changes-1", "added": {}})", "\"added\" must be an array"},
      {R"({"format": "objmap-changes-1", "moved": [{"id": 7, "class": "chair",
          "to": [5, 0, 0]}]})",
       "moved[0]: \"from\" must be 3 finite numbers"},
      {R"({"format": "objmap-changes-1", "removed": [{"class": "cup", "position": [1, 0, 0]}]})",
       "removed[0]: \"id\" (an integer) is missing"},
      {R"({"format": "objmap-changes-1", "added": [{"id": 1, "class": "mug",
          "position": [1, 0, 0]}]})",
       "added[0]: class 'mug' is not a COCO class"},
      {R"({"format": "objmap-changes-1", "added": [{"id": 1, "class": "cup",
          "position": [1, 0]}]})",
       "added[0]: \"position\" must be 3 finite numbers"},
      {R"({"format": "objmap-changes-1", "added": [)", "not valid JSON"},
  };
  for (const Case& c : simulator_cases) {
    const std::string path = Write("truth.json", c.text);
    std::vector<GroundTruthChange> changes;
    std::string why;
    EXPECT_FALSE(ReadGroundTruthChanges(path, &changes, &why)) << c.text;
    EXPECT_EQ(why.rfind(path, 0), 0u) << why;
    EXPECT_NE(why.find(c.reason), std::string::npos) << why;
  }
  const std::vector<Case> map_cases = {
      {R"({"format": "objmap-changes-1", "added": []})",
       "\"format\" is 'objmap-changes-1', expected 'objmap-map-changes-1'"},
      {R"({"format": "objmap-map-changes-1"})", "\"changes\" (an array) is missing"},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "vanished",
          "object_id": 1, "class": "cup", "session_id": 2, "position": [0, 0, 0]}]})",
       "changes[0]: \"kind\" must be \"added\", \"removed\" or \"moved\""},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "added",
          "object_id": 1, "class": "cup", "session_id": "two", "position": [0, 0, 0]}]})",
       "changes[0]: \"session_id\" must be an integer"},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "added",
          "class": "cup", "session_id": 2, "position": [0, 0, 0]}]})",
       "changes[0]: \"object_id\" (an integer) is missing"},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "moved",
          "object_id": 1, "class": "cup", "session_id": 2, "position": [0, 0, 0]}]})",
       "changes[0]: \"from\" must be 3 finite numbers"},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "added",
          "object_id": 1, "class": "cup", "session_id": 2, "position": [0, 0, 0],
          "min": [0, 0, 0]}]})",
       "changes[0]: \"max\" must be 3 finite numbers"},
      {R"({"format": "objmap-map-changes-1", "changes": [{"kind": "added",
          "object_id": 1, "class": "cup", "session_id": 2, "position": [0, 0, 0],
          "stamp": "noon"}]})",
       "changes[0]: \"stamp\" must be a finite number"},
  };
  for (const Case& c : map_cases) {
    const std::string path = Write("reported.json", c.text);
    std::vector<ReportedChange> changes;
    std::string why;
    EXPECT_FALSE(ReadReportedChanges(path, &changes, &why)) << c.text;
    EXPECT_EQ(why.rfind(path, 0), 0u) << why;
    EXPECT_NE(why.find(c.reason), std::string::npos) << why;
  }
  std::vector<ReportedChange> changes;
  std::string why;
  EXPECT_FALSE(ReadReportedChanges((dir_ / "absent.json").string(), &changes, &why));
  EXPECT_NE(why.find("absent.json: cannot be opened"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
