// The inventory must not depend on how keyframes are picked: one synthetic scene, mapped with
// keyframes chosen by camera motion (the default), every 5th frame and every frame, gives the
// same inventory within one object, and that inventory is right against the ground truth.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli/run_objmap.h"

namespace {

namespace fs = std::filesystem;

using objmap::testing::RunCommand;
using Inventory = std::map<std::string, int>;

Inventory ReadInventory(const fs::path& map_dir) {
  std::ifstream in(map_dir / "objects.json");
  const nlohmann::json objects = nlohmann::json::parse(in)["objects"];
  Inventory inventory;
  for (const nlohmann::json& object : objects) {
    if (object["in_inventory"].get<bool>()) ++inventory[object["class"].get<std::string>()];
  }
  return inventory;
}

// Objects one inventory has and the other has not, over all classes.
int Difference(const Inventory& a, const Inventory& b) {
  std::set<std::string> classes;
  for (const auto& [name, count] : a) classes.insert(name);
  for (const auto& [name, count] : b) classes.insert(name);
  int difference = 0;
  for (const std::string& name : classes) {
    const int count_a = a.count(name) > 0 ? a.at(name) : 0;
    const int count_b = b.count(name) > 0 ? b.at(name) : 0;
    difference += std::abs(count_a - count_b);
  }
  return difference;
}

std::string Describe(const Inventory& inventory) {
  std::string text;
  for (const auto& [name, count] : inventory) text += name + " " + std::to_string(count) + ", ";
  return text;
}

class KeyframePolicy : public ::testing::TestWithParam<const char*> {};

TEST_P(KeyframePolicy, InventoryIsTheSameForMotionEveryFifthAndEveryFrame) {
  const std::string kind = GetParam();
  const fs::path dir = fs::temp_directory_path() /
                       ("objmap_keyframe_policy_" + kind + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string scene = (dir / kind).string();
  const std::string cli = OBJMAP_CLI_PATH;
  // 120 frames along the 120 degree sweep: a frame a degree, as a camera moving slowly.
  objmap::testing::CommandResult run = RunCommand(std::string(OBJMAP_SIM_PATH) + " --out " +
                                                  scene + " --kind " + kind +
                                                  " --seed 17 --frames 120");
  ASSERT_EQ(run.exit_code, 0) << run.output;

  // A coarse OctoMap: the test is about objects, and every-frame integration at 1 cm would
  // take most of its time.
  const std::string common = " --detections " + scene + "/detections.json" +
                             " --set occupancy.resolution_m=0.05";
  const std::map<std::string, std::string> policies = {
      {"motion", ""}, {"nth5", " --every-nth-frame 5"}, {"every", " --every-frame"}};
  std::map<std::string, Inventory> inventories;
  std::map<std::string, nlohmann::json> scores;
  for (const auto& [name, flags] : policies) {
    const std::string map = scene + "-" + name;
    run = RunCommand(cli + " map " + scene + common + flags + " --out " + map);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    inventories[name] = ReadInventory(map);
    // Objects only: the coarse OctoMap cannot be scored against the 1 cm seen surface.
    fs::remove(fs::path(map) / "map.bt");
    run = RunCommand("(" + cli + " eval " + map + " --gt " + scene +
                     "/ground_truth.json --json 2>/dev/null)");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    scores[name] = nlohmann::json::parse(run.output)["all"];
  }
  for (const auto& [name, inventory] : inventories) {
    SCOPED_TRACE(name + ": " + Describe(inventory));
    EXPECT_LE(Difference(inventory, inventories["motion"]), 1)
        << "motion: " << Describe(inventories["motion"]);
    // A stable inventory must also be the scene's (an empty one would be stable): more than half
    // of the real objects found, and at least three of four claims true. These are guards
    // against regressions, below what objmap reaches on the four kinds pooled
    // (docs/evaluation.md), not its goals.
    const nlohmann::json& all = scores[name];
    EXPECT_GT(all["tp"].get<int>(), 0.5 * all["real"].get<int>()) << all.dump();
    EXPECT_GE(all["precision"].get<double>(), 0.75) << all.dump();
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(SyntheticKinds, KeyframePolicy,
                         ::testing::Values("desk", "kitchen"));

}  // namespace
