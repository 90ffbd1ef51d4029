// The chain the README's main command runs, on a short synthetic sequence: objmap_sim writes a
// desk with drifting odometry, `objmap map` maps it with the ground-truth detections (once as
// is, once with the corrected poses applied afterwards), `objmap eval` scores both.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/run_objmap.h"

namespace {

namespace fs = std::filesystem;

using objmap::testing::RunCommand;

TEST(SimPipeline, DriftingDeskMapsScoresAndRegeneratesWithCorrectedPoses) {
  const fs::path dir =
      fs::temp_directory_path() / ("objmap_sim_pipeline_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string scene = (dir / "desk").string();
  const std::string cli = OBJMAP_CLI_PATH;
  objmap::testing::CommandResult run =
      RunCommand(std::string(OBJMAP_SIM_PATH) + " --out " + scene +
                 " --kind desk --seed 4 --frames 12 --drift --procedural");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  ASSERT_TRUE(fs::exists(dir / "desk" / "corrected_poses.txt"));

  run = RunCommand(cli + " map " + scene + " --detections " + scene + "/detections.json --out " +
                   scene + "-map");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  run =
      RunCommand(cli + " map " + scene + " --detections " + scene + "/detections.json" +
                 " --corrected-poses " + scene + "/corrected_poses.txt --out " + scene + "-fixed");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // Every keyframe but the first moved back to its true pose.
  EXPECT_NE(run.output.find("corrected poses: "), std::string::npos) << run.output;

  double accuracy[2] = {0.0, 0.0};
  int k = 0;
  for (const char* map : {"-map", "-fixed"}) {
    // JSON on stdout; stderr holds OctoMap's own messages ("Reading binary octree ...").
    run = RunCommand("(" + cli + " eval " + scene + map + " --gt " + scene +
                     "/ground_truth.json --json 2>/dev/null)");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json scores = nlohmann::json::parse(run.output);
    EXPECT_GT(scores["all"]["tp"].get<int>(), 0) << run.output;
    accuracy[k++] = scores["mean_model_to_surface_m"].get<double>();
    // The OctoMap is scored against the seen surface the simulator wrote.
    ASSERT_TRUE(scores.contains("occupancy")) << run.output;
    EXPECT_GT(scores["occupancy"]["occupied"].get<int>(), 0);
    EXPECT_GT(scores["occupancy"]["structure_surface"].get<int>(), 0);
  }
  // The corrected map's models lie closer to the real surfaces than the drifted map's.
  EXPECT_GT(accuracy[0], 0.0);
  EXPECT_LT(accuracy[1], accuracy[0]);
  fs::remove_all(dir);
}

// Drifting scenes mapped with poses the odometry tracks from the frames (their pose files unused
// but for the first, the origin): the trajectory within 2 cm of the truth, and the map scoring
// within 0.05 of the map made at the true poses. Two kinds, two seeds.
TEST(SimPipeline, DriftingScenesMappedWithEstimatedPosesScoreLikeTheTruePoses) {
  const fs::path dir =
      fs::temp_directory_path() / ("objmap_sim_estimate_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string cli = OBJMAP_CLI_PATH;
  for (const auto& [kind, seed] : {std::pair<std::string, int>{"desk", 4}, {"office", 7}}) {
    const std::string scene = (dir / (kind + std::to_string(seed))).string();
    objmap::testing::CommandResult run =
        RunCommand(std::string(OBJMAP_SIM_PATH) + " --out " + scene + " --kind " + kind +
                   " --seed " + std::to_string(seed) + " --frames 90 --drift --procedural");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const std::string detections = " --detections " + scene + "/detections.json";
    run = RunCommand(cli + " map " + scene + detections + " --poses estimate --out " + scene +
                     "-estimated");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    // The truth: corrected_poses.txt (frame index first) as a TUM trajectory (index / 30 s, the
    // stamps objmap map gives frames without their own).
    {
      std::ifstream corrected(scene + "/corrected_poses.txt");
      std::ofstream truth(scene + "/truth.txt");
      std::string line;
      while (std::getline(corrected, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        long index = 0;
        fields >> index;
        std::string rest;
        std::getline(fields, rest);
        truth << index / 30.0 << rest << "\n";
      }
    }
    run = RunCommand("(" + cli + " eval-trajectory " + scene + "-estimated/trajectory.txt " +
                     scene + "/truth.txt --json 2>/dev/null)");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const double ate = nlohmann::json::parse(run.output)["ate_rmse_m"].get<double>();
    EXPECT_LT(ate, 0.02) << kind;
    // The map at the true poses: the drifting one regenerated with them.
    run = RunCommand(cli + " map " + scene + detections + " --corrected-poses " + scene +
                     "/corrected_poses.txt --out " + scene + "-true");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    double precision[2], recall[2];
    int k = 0;
    for (const char* map : {"-true", "-estimated"}) {
      run = RunCommand("(" + cli + " eval " + scene + map + " --gt " + scene +
                       "/ground_truth.json --json 2>/dev/null)");
      ASSERT_EQ(run.exit_code, 0) << run.output;
      const nlohmann::json scores = nlohmann::json::parse(run.output);
      precision[k] = scores["all"]["precision"].get<double>();
      recall[k++] = scores["all"]["recall"].get<double>();
    }
    std::printf("%s %d: ATE %.4f m; precision %.3f / %.3f, recall %.3f / %.3f (true poses / "
                "estimated)\n",
                kind.c_str(), seed, ate, precision[0], precision[1], recall[0], recall[1]);
    EXPECT_GT(recall[0], 0.5) << kind;
    EXPECT_NEAR(precision[1], precision[0], 0.05) << kind;
    EXPECT_NEAR(recall[1], recall[0], 0.05) << kind;
  }
  fs::remove_all(dir);
}

}  // namespace
