// `objmap ingest --resume` against the real objmap_server: a run cut short (here by
// --max-keyframes, then a server killed with SIGKILL and restarted) goes on where the server's
// keyframes end, and the map ends with the keyframes of one whole run, none twice.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <set>

#include "cli/run_objmap.h"
#include "integration/server_process.h"
#include "objmap/client.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> KeyframeNames(const std::string& address) {
  MapClient client(address);
  v1::ListKeyframesResponse listed;
  const grpc::Status status = client.ListKeyframes(v1::ListKeyframesRequest(), &listed);
  EXPECT_TRUE(status.ok()) << status.error_message();
  std::vector<std::string> names;
  for (const v1::KeyframeInfo& keyframe : listed.keyframes()) names.push_back(keyframe.name());
  return names;
}

TEST(IngestResume, ARunCutShortGoesOnWithoutDuplicates) {
  const fs::path dir = fs::temp_directory_path() / ("objmap_resume_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = (dir / "desk").string();
  const testing::CommandResult rendered = testing::RunCommand(
      std::string(OBJMAP_SIM_PATH) + " --out " + scene + " --kind desk --seed 5 --frames 60");
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  const std::string inputs = " " + scene + " --detections " + scene + "/detections.json";

  // The reference: one whole run into a fresh database.
  testing::ServerProcess whole(OBJMAP_SERVER_PATH, (dir / "whole.db").string(),
                               (dir / "whole.log").string(), {"--no-detector"});
  std::string why;
  ASSERT_TRUE(whole.Start(std::chrono::seconds(60), &why)) << why;
  testing::CommandResult run = testing::RunObjmap("ingest" + inputs + " --server " + whole.address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> expected = KeyframeNames(whole.address());
  ASSERT_GE(expected.size(), 5u);

  // A run cut short after 3 keyframes, a server killed and restarted on its file, a resume.
  const std::string db = (dir / "resumed.db").string(), log = (dir / "resumed.log").string();
  auto server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log,
                                                         std::vector<std::string>{"--no-detector"});
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why;
  run = testing::RunObjmap("ingest" + inputs + " --max-keyframes 3 --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  server->Kill(SIGKILL);
  server = std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, db, log,
                                                    std::vector<std::string>{"--no-detector"});
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why << "\n" << server->Log();
  run = testing::RunObjmap("ingest" + inputs + " --resume --server " + server->address());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("resuming: the server holds 3 keyframes"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find(std::to_string(expected.size() - 3) + " added of"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("3 already held"), std::string::npos) << run.output;
  EXPECT_EQ(KeyframeNames(server->address()), expected);
  server.reset();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace objmap
