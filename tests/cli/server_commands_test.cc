// The server commands of `objmap` where no server is needed to judge them: argument errors
// (exit code 2), files checked before any call, and the report of an unreachable server.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "run_objmap.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::RunObjmap;

// Port 1 on loopback: nothing listens there, so every call is refused at once.
constexpr char kNoServer[] = "--server 127.0.0.1:1";

void ExpectOutput(const CommandResult& run, int exit_code, const std::string& text) {
  EXPECT_EQ(run.exit_code, exit_code) << run.output;
  EXPECT_NE(run.output.find(text), std::string::npos) << "expected '" << text << "' in:\n"
                                                      << run.output;
}

TEST(CliServerCommands, ArgumentErrorsExitWithUsage) {
  ExpectOutput(RunObjmap("objects --class"), 2, "--class needs a value");
  ExpectOutput(RunObjmap("objects --region 0 0 0 1 1"), 2, "--region needs 6 values");
  ExpectOutput(RunObjmap("objects --near 0 x 1"), 2, "--near expects numbers, got 'x'");
  ExpectOutput(RunObjmap("objects --limit ten"), 2, "--limit expects a whole number >= 0");
  ExpectOutput(RunObjmap("objects --min-confidence high"), 2,
               "--min-confidence expects a number, got 'high'");
  ExpectOutput(RunObjmap("inventory --since -4"), 2, "--since expects a whole number >= 0");
  ExpectOutput(RunObjmap("inventory --colour"), 2, "unknown option --colour");
  ExpectOutput(RunObjmap("free 0 0 0 1 1"), 2, "missing Z1");
  ExpectOutput(RunObjmap("free 0 0 0 1 one 1"), 2, "Y1 expects a number, got 'one'");
  ExpectOutput(RunObjmap("status --timeout -1"), 2, "--timeout expects seconds >= 0");
  ExpectOutput(RunObjmap("status --server"), 2, "--server needs a value");
  ExpectOutput(RunObjmap("export --region 0 0 0 1 1 1"), 2, "at least one of --octomap");
  ExpectOutput(RunObjmap("update-poses"), 2, "usage: objmap update-poses");
  ExpectOutput(RunObjmap("ingest"), 2, "usage: objmap ingest");
  ExpectOutput(RunObjmap("keyframes --limit -1"), 2, "--limit expects a whole number >= 0");
  ExpectOutput(RunObjmap("keyframes extra"), 2, "usage: objmap keyframes");
  ExpectOutput(RunObjmap("ingest some/dir --max-keyframes 2.5"), 2,
               "--max-keyframes expects a whole number >= 0, got '2.5'");
}

TEST(CliServerCommands, HelpExitsZero) {
  for (const char* command :
       {"ingest", "inventory", "objects", "free", "export", "update-poses", "keyframes",
        "status"}) {
    ExpectOutput(RunObjmap(std::string(command) + " --help"), 0, "--server ADDR");
  }
}

TEST(CliServerCommands, UnreachableServerPrintsTheStatusCode) {
  for (const std::string command : {"status", "keyframes", "inventory --json", "objects --class cup",
                                    "free 0 0 0 1 1 1", "export --octomap /nonexistent/x.bt"}) {
    ExpectOutput(RunObjmap(command + " " + kNoServer), 1,
                 "objmap " + command.substr(0, command.find(' ')) + ": UNAVAILABLE: ");
  }
}

TEST(CliServerCommands, FilesAreCheckedBeforeTheServerIsAsked) {
  const fs::path dir =
      fs::temp_directory_path() / ("objmap_cli_server_" + std::to_string(::getpid()));
  fs::create_directories(dir / "empty");
  const std::string poses = (dir / "poses.txt").string();
  std::ofstream(poses) << "# id tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n";
  ExpectOutput(RunObjmap("update-poses " + poses + " " + kNoServer), 1,
               "objmap update-poses: " + poses + ": line 3: expected 8 fields");
  ExpectOutput(RunObjmap("update-poses " + (dir / "none.txt").string() + " " + kNoServer), 1,
               "none.txt: cannot be opened");
  ExpectOutput(RunObjmap("ingest " + (dir / "empty").string() + " " + kNoServer), 1,
               "objmap ingest: ");
  // A good poses file gets as far as the server.
  std::ofstream(poses) << "0 0 0 0 0 0 0 1\n";
  ExpectOutput(RunObjmap("update-poses " + poses + " --wait " + kNoServer), 1,
               "objmap update-poses: UNAVAILABLE");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace objmap
