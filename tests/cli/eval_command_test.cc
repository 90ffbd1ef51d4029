// `objmap eval` as a user runs it: a map folder scored against ground truth and against counts,
// and the errors that name what is wrong.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run_objmap.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::RunObjmap;

class EvalCommand : public ::testing::Test {
 protected:
  EvalCommand()
      : dir_(fs::temp_directory_path() / ("objmap_eval_cli_" + std::to_string(getpid()))) {
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "map" / "objects");
    // Two cups in the map: one where the real cup is, one where nothing is; the real chair is
    // not in the map.
    std::ofstream(dir_ / "map" / "objects.json") << R"({"objects": [
      {"id": 1, "class": "cup", "in_inventory": true, "centroid": [0, 0, 0.75],
       "bbox_min": [-0.04, -0.04, 0.7], "bbox_max": [0.04, 0.04, 0.8]},
      {"id": 2, "class": "cup", "in_inventory": true, "centroid": [3, 3, 3],
       "bbox_min": [2.96, 2.96, 2.95], "bbox_max": [3.04, 3.04, 3.05]}]})";
    std::ofstream(dir_ / "gt.json") << R"({"objects": [
      {"id": 10, "class": "cup", "pose": [1,0,0,0, 0,1,0,0, 0,0,1,0.75, 0,0,0,1],
       "size": [0.08, 0.08, 0.1]},
      {"id": 11, "class": "chair", "pose": [1,0,0,1, 0,1,0,0, 0,0,1,0.45, 0,0,0,1],
       "size": [0.5, 0.5, 0.9]}]})";
    std::ofstream(dir_ / "counts.json") << R"({"cup": 1, "chair": [1, 2]})";
  }
  ~EvalCommand() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(EvalCommand, GroundTruthGivesThePaperCountsAsJson) {
  const auto run = RunObjmap("eval " + Path("map") + " --gt " + Path("gt.json") + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json scores = nlohmann::json::parse(run.output);
  EXPECT_EQ(scores["all"]["tp"], 1);
  EXPECT_EQ(scores["all"]["fp"], 1);
  EXPECT_EQ(scores["all"]["fn"], 1);
  EXPECT_EQ(scores["classes"]["chair"]["fn"], 1);
  EXPECT_DOUBLE_EQ(scores["all"]["precision"].get<double>(), 0.5);
  EXPECT_EQ(scores["matches"][0]["mapped_id"], 1);
}

TEST_F(EvalCommand, CountsAreScoredPerClassInATable) {
  const auto run = RunObjmap("eval " + Path("map") + " --inventory " + Path("counts.json"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // cup: 2 mapped, 1 expected -> 1 TP, 1 FP; chair: none of at least 1 -> 1 FN.
  EXPECT_NE(run.output.find("cup                  1      2    1    1    0"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("chair                1      0    0    0    1"), std::string::npos)
      << run.output;
}

TEST_F(EvalCommand, BadUseAndBadFilesAreNamed) {
  EXPECT_EQ(RunObjmap("eval " + Path("map")).exit_code, 2);
  EXPECT_EQ(RunObjmap("eval " + Path("map") + " --gt a --inventory b").exit_code, 2);
  const auto missing = RunObjmap("eval " + Path("nowhere") + " --gt " + Path("gt.json"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("nowhere: not a folder"), std::string::npos) << missing.output;
  std::ofstream(dir_ / "bad.json") << R"({"objects": [{"id": 1, "class": "mug"}]})";
  const auto bad = RunObjmap("eval " + Path("map") + " --gt " + Path("bad.json"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("bad.json: objects[0]: class 'mug' is not a COCO class"),
            std::string::npos)
      << bad.output;
}

// `objmap eval-trajectory`: a reference trajectory and an estimate 2 cm off along x in every
// other pose, in TUM files.
class EvalTrajectoryCommand : public EvalCommand {
 protected:
  EvalTrajectoryCommand() {
    std::ofstream reference(dir_ / "reference.txt");
    std::ofstream estimated(dir_ / "estimated.txt");
    reference << "# stamp tx ty tz qx qy qz qw\n";
    for (int i = 0; i < 100; ++i) {
      const double stamp = 1.0 + i / 30.0, x = 0.05 * i;
      reference << stamp << " " << x << " 0 1 0 0 0 1\n";
      estimated << stamp + 0.001 << " " << x + (i % 2 == 0 ? 0.02 : 0.0) << " 0 1 0 0 0 1\n";
    }
  }
};

TEST_F(EvalTrajectoryCommand, PrintsTheAbsoluteAndRelativeErrors) {
  const auto run = RunObjmap("eval-trajectory " + Path("estimated.txt") + " " +
                             Path("reference.txt") + " --json --errors " + Path("ate.txt"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json scores = nlohmann::json::parse(run.output);
  EXPECT_EQ(scores["matched"], 100);
  // Aligned, the two halves sit 1 cm either side: every error is 1 cm.
  EXPECT_NEAR(scores["ate_rmse_m"].get<double>(), 0.01, 1e-4);
  EXPECT_NEAR(scores["ate_max_m"].get<double>(), 0.01, 1e-4);
  EXPECT_GT(scores["rpe_pairs"].get<int>(), 50);
  std::ifstream errors(Path("ate.txt"));
  std::string header, line;
  std::getline(errors, header);
  int lines = 0;
  while (std::getline(errors, line)) ++lines;
  EXPECT_EQ(lines, 100);

  const auto table = RunObjmap("eval-trajectory " + Path("estimated.txt") + " " +
                               Path("reference.txt"));
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_NE(table.output.find("ATE RMSE 0.0100 m"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("RPE over 1.00 m"), std::string::npos) << table.output;
}

TEST_F(EvalTrajectoryCommand, BadInputIsNamed) {
  std::ofstream(dir_ / "bad.txt") << "1.0 0 0 0 0 0 0\n";
  auto run = RunObjmap("eval-trajectory " + Path("bad.txt") + " " + Path("reference.txt"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("bad.txt:1"), std::string::npos) << run.output;
  run = RunObjmap("eval-trajectory " + Path("estimated.txt") + " " + Path("reference.txt") +
                  " --max-dt 0.0001");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("0 of 100 estimated poses"), std::string::npos) << run.output;
  run = RunObjmap("eval-trajectory " + Path("estimated.txt"));
  EXPECT_EQ(run.exit_code, 2) << run.output;
}

}  // namespace
}  // namespace objmap
