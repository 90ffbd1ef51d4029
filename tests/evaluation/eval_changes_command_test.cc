// `objmap eval --changes` as a user runs it: a map folder's reported changes scored against the
// simulator's, as a table and as JSON, alone and with --gt, and the errors that name what is
// wrong.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli/run_objmap.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::RunObjmap;

class EvalChangesCommand : public ::testing::Test {
 protected:
  EvalChangesCommand()
      : dir_(fs::temp_directory_path() / ("objmap_eval_changes_" + std::to_string(getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "map");
    // Between the sessions a cup was taken away, a chair moved 2 m and a dining table put in.
    std::ofstream(dir_ / "changes.json") << R"({"format": "objmap-changes-1", "kind": "office",
      "seed": 3,
      "removed": [{"id": 4, "class": "cup", "name": "cup_1", "position": [1, 0, 0.8]}],
      "moved": [{"id": 7, "class": "chair", "name": "chair_1", "from": [3, 0, 0.45],
                 "to": [5, 0, 0.45], "other_support": false}],
      "added": [{"id": 21, "class": "dining table", "name": "table_2",
                 "position": [0, 3, 0.375]}]})";
    std::ofstream(dir_ / "gt_before.json") << R"({"objects": [
      {"id": 4, "class": "cup", "pose": [1,0,0,1, 0,1,0,0, 0,0,1,0.8, 0,0,0,1],
       "size": [0.08, 0.08, 0.1]},
      {"id": 7, "class": "chair", "pose": [1,0,0,3, 0,1,0,0, 0,0,1,0.45, 0,0,0,1],
       "size": [0.5, 0.5, 0.9]}]})";
    std::ofstream(dir_ / "gt_after.json") << R"({"objects": [
      {"id": 7, "class": "chair", "pose": [1,0,0,5, 0,1,0,0, 0,0,1,0.45, 0,0,0,1],
       "size": [0.5, 0.5, 0.9]},
      {"id": 21, "class": "dining table", "pose": [1,0,0,0, 0,1,0,3, 0,0,1,0.375, 0,0,0,1],
       "size": [1.6, 0.9, 0.75]}]})";
    // The map: the cup's removal and the chair's move under its old id (session 2), the table
    // 0.6 m off its centre (near enough for a 1.6 m table, not for the 0.25 m floor), and a
    // spurious addition from session 1.
    std::ofstream(dir_ / "map" / "changes.json") << R"({"format": "objmap-map-changes-1",
      "changes": [
        {"kind": "added", "object_id": 2, "class": "tv", "session_id": 1, "keyframe_id": 3,
         "stamp": 0.5, "position": [9, 9, 1]},
        {"kind": "removed", "object_id": 5, "class": "cup", "session_id": 2, "keyframe_id": 40,
         "stamp": 10.0, "position": [1.02, 0, 0.8], "min": [0.98, -0.04, 0.75],
         "max": [1.06, 0.04, 0.85]},
        {"kind": "moved", "object_id": 6, "class": "chair", "session_id": 2, "keyframe_id": 44,
         "stamp": 11.0, "position": [5.05, 0, 0.45], "from": [3, 0.05, 0.45]},
        {"kind": "added", "object_id": 30, "class": "dining table", "session_id": 2,
         "keyframe_id": 57, "stamp": 12.3, "position": [0.6, 3, 0.375]}]})";
    std::ofstream(dir_ / "map" / "objects.json") << R"({"objects": [
      {"id": 6, "class": "chair", "in_inventory": true, "centroid": [5, 0, 0.45],
       "bbox_min": [4.75, -0.25, 0], "bbox_max": [5.25, 0.25, 0.9]},
      {"id": 30, "class": "dining table", "in_inventory": true, "centroid": [0.6, 3, 0.375],
       "bbox_min": [-0.2, 2.55, 0], "bbox_max": [1.4, 3.45, 0.75]}]})";
  }
  ~EvalChangesCommand() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Changes() const {
    return "eval " + Path("map") + " --changes " + Path("changes.json");
  }
  fs::path dir_;
};

TEST_F(EvalChangesCommand, ScoresEachKindAsJson) {
  const auto run = RunObjmap(Changes() + " --gt-before " + Path("gt_before.json") + " --gt " +
                             Path("gt_after.json") + " --since-session 2 --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // With --gt the map's objects are scored too; the change scores are under "changes".
  const nlohmann::json document = nlohmann::json::parse(run.output);
  EXPECT_EQ(document["all"]["tp"], 2);  // the map's chair and table stand for the real ones
  const nlohmann::json& scores = document["changes"];
  for (const char* kind : {"removed", "moved", "added", "all"}) {
    EXPECT_DOUBLE_EQ(scores[kind]["precision"].get<double>(), 1.0) << kind << run.output;
    EXPECT_DOUBLE_EQ(scores[kind]["recall"].get<double>(), 1.0) << kind << run.output;
    EXPECT_EQ(scores[kind]["fp"], 0) << kind;
    EXPECT_EQ(scores[kind]["fn"], 0) << kind;
  }
  EXPECT_EQ(scores["all"]["tp"], 3);
  EXPECT_EQ(scores["moved_kept_id"], 1);
  EXPECT_EQ(scores["moved_total"], 1);
  EXPECT_EQ(scores["since_session"], 2);
}

TEST_F(EvalChangesCommand, EverySessionCountsByDefaultAndSizesWidenTheMatch) {
  const auto run = RunObjmap(Changes() + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json scores = nlohmann::json::parse(run.output);
  // Session 1's tv counts now; without the ground truth's sizes the table is 0.6 m too far.
  EXPECT_EQ(scores["added"]["reported"], 2);
  EXPECT_EQ(scores["added"]["tp"], 0);
  EXPECT_EQ(scores["added"]["fp"], 2);
  EXPECT_EQ(scores["added"]["fn"], 1);
  EXPECT_TRUE(scores["since_session"].is_null());
}

TEST_F(EvalChangesCommand, PrintsATablePerKind) {
  const auto run = RunObjmap(Changes() + " --since-session 2 --gt " + Path("gt_after.json") +
                             " --gt-before " + Path("gt_before.json"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // With --gt, the objects' table comes first, then the changes'.
  const std::size_t changes_at = run.output.find("change detection (map reports of sessions >= 2)");
  ASSERT_NE(changes_at, std::string::npos) << run.output;
  EXPECT_LT(run.output.find("precision"), changes_at) << run.output;
  EXPECT_NE(run.output.find("removed      1        1    1    0    0     1.000   1.000"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("all          3        3    3    0    0     1.000   1.000"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("moved objects that kept their id: 1 of 1"), std::string::npos)
      << run.output;
}

TEST_F(EvalChangesCommand, InventoryCountsAndChangesAreOneJsonDocument) {
  std::ofstream(dir_ / "counts.json") << R"({"chair": 1, "dining table": 1})";
  const auto run =
      RunObjmap(Changes() + " --inventory " + Path("counts.json") + " --since-session 2 --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json scores = nlohmann::json::parse(run.output);
  EXPECT_EQ(scores["all"]["tp"], 2);
  EXPECT_EQ(scores["changes"]["moved"]["tp"], 1);
  // No ground truth gave the table's size: 0.6 m is beyond the 0.25 m floor.
  EXPECT_EQ(scores["changes"]["added"]["fn"], 1);
}

TEST_F(EvalChangesCommand, MoveReportedAsRemovalAndAdditionIsNotKept) {
  std::ofstream(dir_ / "map" / "changes.json") << R"({"format": "objmap-map-changes-1",
    "changes": [
      {"kind": "removed", "object_id": 6, "class": "chair", "session_id": 2,
       "position": [3, 0, 0.45]},
      {"kind": "added", "object_id": 31, "class": "chair", "session_id": 2,
       "position": [5, 0, 0.45]}]})";
  const auto run = RunObjmap(Changes() + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json scores = nlohmann::json::parse(run.output);
  EXPECT_EQ(scores["moved"]["fn"], 1);
  EXPECT_EQ(scores["moved_kept_id"], 0);
  EXPECT_EQ(scores["moved_as_removed_and_added"], 1);
  EXPECT_EQ(scores["removed"]["fp"], 1);
  EXPECT_EQ(scores["added"]["fp"], 1);
}

TEST_F(EvalChangesCommand, LookAlikesAreReadAsTheReportsPairThemUnlessAskedNotTo) {
  // A mug taken from the desk, a new mug of the same mesh and size put on the shelf; the map saw
  // one mug go from the desk to the shelf.
  std::ofstream(dir_ / "changes.json") << R"({"format": "objmap-changes-1",
    "removed": [{"id": 4, "class": "cup", "position": [1, 0, 0.8]}],
    "moved": [],
    "added": [{"id": 9, "class": "cup", "position": [4, 0, 1.2]}]})";
  const std::string mesh =
      R"("size": [0.12, 0.09, 0.1], "surface_mesh": {"vertices": [[0,0,0], [0.1,0,0],
       [0,0.1,0]], "triangles": [[0, 1, 2]]}})";
  std::ofstream(dir_ / "gt_before.json") << R"({"objects": [{"id": 4, "class": "cup",
      "pose": [1,0,0,1, 0,1,0,0, 0,0,1,0.8, 0,0,0,1], )"
                                         << mesh << "]}";
  std::ofstream(dir_ / "gt_after.json") << R"({"objects": [{"id": 9, "class": "cup",
      "pose": [1,0,0,4, 0,1,0,0, 0,0,1,1.2, 0,0,0,1], )"
                                        << mesh << "]}";
  std::ofstream(dir_ / "map" / "changes.json") << R"({"format": "objmap-map-changes-1",
    "changes": [{"kind": "moved", "object_id": 6, "class": "cup", "session_id": 2,
                 "position": [4, 0.02, 1.2], "from": [1, 0, 0.8]}]})";
  const std::string given =
      " --gt-before " + Path("gt_before.json") + " --gt " + Path("gt_after.json") + " --json";
  const auto run = RunObjmap(Changes() + given);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json read = nlohmann::json::parse(run.output)["changes"];
  EXPECT_EQ(read["lookalike_groups_reread"], 1) << run.output;
  EXPECT_EQ(read["moved"]["tp"], 1);
  EXPECT_EQ(read["all"]["real"], 1);
  EXPECT_EQ(read["all"]["fp"], 0);
  const auto strict = RunObjmap(Changes() + given + " --lookalikes-as-written");
  ASSERT_EQ(strict.exit_code, 0) << strict.output;
  const nlohmann::json as_written = nlohmann::json::parse(strict.output)["changes"];
  EXPECT_EQ(as_written["lookalike_groups_reread"], 0);
  EXPECT_EQ(as_written["all"]["tp"], 0);
  EXPECT_EQ(as_written["all"]["fn"], 2);
  EXPECT_EQ(as_written["moved"]["fp"], 1);
  // The flag belongs to --changes.
  EXPECT_EQ(RunObjmap("eval " + Path("map") + " --gt " + Path("gt_after.json") +
                      " --lookalikes-as-written")
                .exit_code,
            2);
}

TEST_F(EvalChangesCommand, BadUseAndBadFilesAreNamed) {
  // --since-session and --gt-before belong to --changes; --since-session counts from 1.
  EXPECT_EQ(
      RunObjmap("eval " + Path("map") + " --gt " + Path("gt_after.json") + " --since-session 2")
          .exit_code,
      2);
  EXPECT_EQ(RunObjmap(Changes() + " --since-session 0").exit_code, 2);
  EXPECT_EQ(RunObjmap(Changes() + " --since-session two").exit_code, 2);
  const auto swapped = RunObjmap("eval " + Path("map") + " --changes " + Path("map/changes.json"));
  EXPECT_EQ(swapped.exit_code, 1);
  EXPECT_NE(swapped.output.find("expected 'objmap-changes-1'"), std::string::npos)
      << swapped.output;
  fs::remove(dir_ / "map" / "changes.json");
  const auto missing = RunObjmap(Changes());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("changes.json: cannot be opened"), std::string::npos)
      << missing.output;
  std::ofstream(dir_ / "map" / "changes.json") << R"({"format": "objmap-map-changes-1",
    "changes": [{"kind": "added", "object_id": 1, "class": "cup", "position": [0, 0, 0]}]})";
  EXPECT_EQ(RunObjmap(Changes()).exit_code, 0);  // no sessions to filter by: fine
  const auto no_session = RunObjmap(Changes() + " --since-session 2");
  EXPECT_EQ(no_session.exit_code, 1);
  EXPECT_NE(no_session.output.find(
                "changes.json: changes[0]: \"session_id\" is missing, which --since-session needs"),
            std::string::npos)
      << no_session.output;
  std::ofstream(dir_ / "map" / "changes.json") << R"({"format": "objmap-map-changes-1",
    "changes": [{"kind": "added", "object_id": 1, "class": "cup", "position": [0, "y", 0]}]})";
  const auto bad = RunObjmap(Changes());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("changes.json: changes[0]: \"position\" must be 3 finite numbers"),
            std::string::npos)
      << bad.output;
}

}  // namespace
}  // namespace objmap
