// The real objmap_server and objmap executables with TLS, bearer tokens and one server per
// database: what a user sees on the command line. Needs no data.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "cli/run_objmap.h"
#include "integration/server_process.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;

const std::string kTls = std::string(OBJMAP_SOURCE_DIR) + "/tests/data/tls/";

class ServerSecurity : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("objmap_security_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // A file only its owner reads.
  std::string WriteFile(const std::string& name, const std::string& text) const {
    const std::string path = Path(name);
    std::ofstream(path) << text;
    ::chmod(path.c_str(), 0600);
    return path;
  }

  std::unique_ptr<testing::ServerProcess> Server(const std::string& db,
                                                 std::vector<std::string> arguments) const {
    arguments.insert(arguments.begin(), "--no-detector");
    return std::make_unique<testing::ServerProcess>(OBJMAP_SERVER_PATH, Path(db),
                                                    Path(db + ".log"), arguments);
  }

  fs::path dir_;
};

TEST_F(ServerSecurity, TheCliReachesATlsServerWithItsTokenAndNothingElseDoes) {
  const std::string tokens =
      WriteFile("tokens.txt", "read reader-token-0123456789\nwrite writer-token-0123456789\n");
  auto server = Server("map.db", {"--tls-cert", kTls + "server.pem", "--tls-key",
                                  kTls + "server.key", "--tokens", tokens});
  std::string why;
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why;
  const std::string tls = " --server " + server->address() + " --tls-ca " + kTls + "ca.pem";
  const std::string reader =
      WriteFile("reader.token", "# the fleet's read token\nreader-token-0123456789\n");

  testing::CommandResult status = testing::RunObjmap("status" + tls + " --token-file " + reader);
  EXPECT_EQ(status.exit_code, 0) << status.output;
  EXPECT_NE(status.output.find("keyframes"), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("octomap:       "), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("kept twice"), std::string::npos) << status.output;

  status = testing::RunObjmap("status" + tls);
  EXPECT_EQ(status.exit_code, 1) << status.output;
  EXPECT_NE(status.output.find("UNAUTHENTICATED"), std::string::npos) << status.output;
  status = testing::RunObjmap("status --server " + server->address() + " --token-file " + reader);
  EXPECT_EQ(status.exit_code, 1) << status.output;
  status = testing::RunObjmap("status" + tls + " --token-file " + Path("absent.token"));
  EXPECT_EQ(status.exit_code, 2) << status.output;
  EXPECT_NE(status.output.find("--token-file: " + Path("absent.token")), std::string::npos)
      << status.output;

  // One server per database: a second one on the same file says who holds it and exits.
  const testing::CommandResult second = testing::RunCommand(
      std::string(OBJMAP_SERVER_PATH) + " --no-detector --listen 127.0.0.1:0 --db " +
      Path("map.db"));
  EXPECT_EQ(second.exit_code, 1) << second.output;
  EXPECT_NE(second.output.find("in use by another objmap process (pid " +
                               std::to_string(server->pid())),
            std::string::npos)
      << second.output;
  struct stat info {};
  ASSERT_EQ(::stat(Path("map.db").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
}

TEST_F(ServerSecurity, EveryInterfaceWithoutProtectionNeedsInsecureAndIsWarnedAbout) {
  const testing::CommandResult refused = testing::RunCommand(
      std::string(OBJMAP_SERVER_PATH) + " --no-detector --listen 0.0.0.0:0 --db " +
      Path("map.db"));
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("give --insecure to serve it without"), std::string::npos)
      << refused.output;

  auto server = Server("map.db", {"--listen", "0.0.0.0:0", "--insecure"});
  std::string why;
  ASSERT_TRUE(server->Start(std::chrono::seconds(60), &why)) << why;
  EXPECT_NE(server->Log().find("warning: serving 0.0.0.0:0 without TLS and tokens (--insecure)"),
            std::string::npos)
      << server->Log();
}

}  // namespace
}  // namespace objmap
