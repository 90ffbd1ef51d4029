// The chain the README's main command runs, on a short synthetic sequence: objmap_sim writes a
// desk with drifting odometry, `objmap map` maps it with the ground-truth detections (once as
// is, once with the corrected poses applied afterwards), `objmap eval` scores both.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
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

}  // namespace
