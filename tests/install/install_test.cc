// The install and the one configuration file, as a user meets them: `cmake --install` into a
// fresh prefix, the installed executables run from an unrelated directory, and `objmap map
// --config` / `objmap_server --config` reading and printing the same file.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "cli/run_objmap.h"
#include "http_viewer/http_viewer.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;

std::string ReadText(const fs::path& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// A temporary folder outside the build and source trees, removed at the end.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : path_(fs::temp_directory_path() / ("objmap_" + name + "_" + std::to_string(getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempFolder() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// The resolution of an OctoMap .bt file, from its text header ("res 0.02").
double BtResolution(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::string line;
  for (int i = 0; i < 10 && std::getline(file, line); ++i) {
    if (line.rfind("res ", 0) == 0) return std::stod(line.substr(4));
  }
  return -1.0;
}

const fs::path kModel = fs::path(OBJMAP_MODEL_DIR) / "centernet_coco.pb";

std::string Redkitchen() { return testing::SharedDataPath("redkitchen"); }

// A few redkitchen frames from `folder` (the working directory) with the given executable.
std::string MapCommand(const fs::path& objmap, const fs::path& folder, const std::string& extra) {
  return "cd '" + folder.string() + "' && env -u OBJMAP_MODEL '" + objmap.string() + "' map '" +
         Redkitchen() + "' --out out --max-frames 6 --every-nth-frame 3 " + extra;
}

class Install : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    prefix_ = new TempFolder("install_prefix");
    install_ = RunCommand("cmake --install '" + std::string(OBJMAP_BINARY_DIR) + "' --prefix '" +
                          prefix_->path().string() + "'");
  }
  static void TearDownTestSuite() {
    delete prefix_;
    prefix_ = nullptr;
  }
  static fs::path Prefix() { return prefix_->path(); }

  static TempFolder* prefix_;
  static testing::CommandResult install_;
};
TempFolder* Install::prefix_ = nullptr;
testing::CommandResult Install::install_;

TEST_F(Install, PutsExecutablesModelConfigurationAndLaunchFilesUnderThePrefix) {
  ASSERT_EQ(install_.exit_code, 0) << install_.output;
  EXPECT_TRUE(fs::is_regular_file(Prefix() / "bin/objmap"));
#ifdef OBJMAP_TEST_WITH_SERVER
  EXPECT_TRUE(fs::is_regular_file(Prefix() / "bin/objmap_server"));
#endif
#ifdef OBJMAP_TEST_WITH_ROS
  for (const char* program : {"objmap_node", "objmap_dataset_player"}) {
    EXPECT_TRUE(fs::is_regular_file(Prefix() / "bin" / program)) << program;
    // roslaunch looks in lib/objmap.
    EXPECT_TRUE(fs::is_regular_file(Prefix() / "lib/objmap" / program)) << program;
  }
#endif
  // Nothing goes outside the prefix (catkin's own rules once put its setup files into the
  // configure-time prefix, /usr/local).
  const std::regex installed_line(R"re(-- (Installing|Up-to-date): ([^\n]+))re");
  int installed_files = 0;
  for (auto it =
           std::sregex_iterator(install_.output.begin(), install_.output.end(), installed_line);
       it != std::sregex_iterator(); ++it, ++installed_files) {
    EXPECT_EQ((*it)[2].str().rfind(Prefix().string() + "/", 0), 0u) << (*it)[2].str();
  }
  EXPECT_GT(installed_files, 0) << install_.output;
  const fs::path share = Prefix() / "share/objmap";
  EXPECT_TRUE(fs::is_regular_file(share / "launch/objmap.rviz"));
  EXPECT_EQ(ReadText(share / "objmap.example.yaml"),
            ReadText(fs::path(OBJMAP_SOURCE_DIR) / "server/core/config/objmap.example.yaml"));
  // The installed launch files load the installed configuration, which exists there.
  for (const char* launch : {"objmap.launch", "objmap_openni2.launch"}) {
    const std::string text = ReadText(share / "launch" / launch);
    ASSERT_FALSE(text.empty()) << launch;
    std::smatch match;
    const std::regex config_default(R"re(name="config" default="\$\(find objmap\)/([^"]+)")re");
    ASSERT_TRUE(std::regex_search(text, match, config_default)) << launch;
    EXPECT_TRUE(fs::is_regular_file(share / match[1].str())) << launch << ": " << match[1];
  }
  if (!fs::is_regular_file(kModel)) {
    GTEST_SKIP() << "SKIPPED: needs the detector model " << kModel
                 << " (scripts/fetch_model.sh) to check that it is installed";
  }
  EXPECT_EQ(fs::file_size(share / "models/centernet_coco.pb"), fs::file_size(kModel));
}

TEST_F(Install, InstalledObjmapFindsItsModelFromAnyDirectory) {
  ASSERT_EQ(install_.exit_code, 0) << install_.output;
  if (!testing::Exists(Redkitchen()) || !fs::is_regular_file(kModel)) {
    GTEST_SKIP() << "SKIPPED: needs ../shared/data/redkitchen and the detector model " << kModel;
  }
  const TempFolder elsewhere("install_elsewhere");
  const fs::path objmap = Prefix() / "bin/objmap";
  const fs::path installed_model = Prefix() / "share/objmap/models/centernet_coco.pb";

  const testing::CommandResult run = RunCommand(MapCommand(objmap, elsewhere.path(), ""));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("detector model: " + installed_model.string()), std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::is_regular_file(elsewhere.path() / "out/map.bt"));
  EXPECT_TRUE(fs::is_regular_file(elsewhere.path() / "out/objects.json"));

  // Without the installed model: the message lists where it looked, and an installed binary
  // does not reach back into the source tree.
  fs::rename(installed_model, installed_model.string() + ".moved");
  const testing::CommandResult missing = RunCommand(MapCommand(objmap, elsewhere.path(), ""));
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("next to the executable: " + installed_model.string()),
            std::string::npos)
      << missing.output;
  EXPECT_NE(missing.output.find("$OBJMAP_MODEL: not set"), std::string::npos) << missing.output;
  EXPECT_EQ(missing.output.find("source tree"), std::string::npos) << missing.output;

  // The environment variable is the next place.
  const testing::CommandResult from_env =
      RunCommand("cd '" + elsewhere.path().string() + "' && OBJMAP_MODEL='" +
                 installed_model.string() + ".moved' '" + objmap.string() + "' map '" +
                 Redkitchen() + "' --out out2 --max-frames 3 --every-frame");
  EXPECT_EQ(from_env.exit_code, 0) << from_env.output;
  EXPECT_NE(from_env.output.find("detector model: " + installed_model.string() + ".moved"),
            std::string::npos)
      << from_env.output;
  fs::rename(installed_model.string() + ".moved", installed_model);
}

// After `source PREFIX/setup.bash` in an otherwise bare environment, the ROS tools find objmap
// and objmap_msgs: the Python messages (rospy, rosservice, rostopic), the definitions (rosmsg)
// and the launch files with RViz (roslaunch).
TEST_F(Install, SourcingTheInstalledSetupBashPutsObjmapOnTheRosPaths) {
  ASSERT_EQ(install_.exit_code, 0) << install_.output;
#ifndef OBJMAP_TEST_WITH_ROS
  GTEST_SKIP() << "SKIPPED: needs a build with the ROS node (catkin and the ROS packages)";
#else
  for (const char* file :
       {"setup.bash", "setup.sh", "_setup_util.py", ".catkin", "share/objmap_msgs/package.xml",
        "share/objmap_msgs/msg/MapChange.msg", "share/objmap_msgs/srv/IsFree.srv",
        "lib/python3/dist-packages/objmap_msgs/srv/_IsFree.py",
        "lib/python3/dist-packages/objmap_msgs/msg/_MapChange.py"}) {
    EXPECT_TRUE(fs::exists(Prefix() / file)) << file;
  }
  const TempFolder elsewhere("install_ros");
  const std::string in_bare_shell =
      "cd '" + elsewhere.path().string() +
      "' && env -i HOME=\"$HOME\" PATH=/usr/bin:/bin bash -c \"source '" +
      (Prefix() / "setup.bash").string() + "' && ";
  const testing::CommandResult python =
      RunCommand(in_bare_shell +
                 "/usr/bin/python3 -c 'from objmap_msgs.srv import IsFree; print(IsFree._type)'\"");
  EXPECT_EQ(python.exit_code, 0) << python.output;
  EXPECT_NE(python.output.find("objmap_msgs/IsFree"), std::string::npos) << python.output;
  const testing::CommandResult tools =
      RunCommand("command -v rossrv roslaunch && /usr/bin/python3 -c 'import rospy'");
  if (tools.exit_code != 0) {
    GTEST_SKIP() << "SKIPPED: needs the ROS Python tools (rossrv, roslaunch, rospy: bash "
                    "scripts/setup.sh) for the rest: "
                 << tools.output;
  }
  const testing::CommandResult definition =
      RunCommand(in_bare_shell + "rossrv show objmap_msgs/IsFree\"");
  EXPECT_EQ(definition.exit_code, 0) << definition.output;
  EXPECT_NE(definition.output.find("bool unknown_is_free"), std::string::npos) << definition.output;
  const testing::CommandResult launch =
      RunCommand(in_bare_shell + "roslaunch --nodes objmap objmap.launch rviz:=true\"");
  EXPECT_EQ(launch.exit_code, 0) << launch.output;
  EXPECT_NE(launch.output.find("/objmap_node"), std::string::npos) << launch.output;
  EXPECT_NE(launch.output.find("/objmap_rviz"), std::string::npos) << launch.output;
#endif
}

TEST_F(Install, InstalledServerReadsTheInstalledConfiguration) {
  ASSERT_EQ(install_.exit_code, 0) << install_.output;
#ifndef OBJMAP_TEST_WITH_SERVER
  GTEST_SKIP() << "SKIPPED: needs objmap_server (a build with OBJMAP_WITH_GRPC=ON)";
#else
  const TempFolder elsewhere("install_server");
  const fs::path config = Prefix() / "share/objmap/objmap.example.yaml";
  const testing::CommandResult server = RunCommand(
      "cd '" + elsewhere.path().string() + "' && '" + (Prefix() / "bin/objmap_server").string() +
      "' --print-config --config '" + config.string() + "'");
  ASSERT_EQ(server.exit_code, 0) << server.output;
  const testing::CommandResult map = RunCommand(
      "cd '" + elsewhere.path().string() + "' && '" + (Prefix() / "bin/objmap").string() +
      "' map --print-config --config '" + config.string() + "'");
  ASSERT_EQ(map.exit_code, 0) << map.output;
  EXPECT_EQ(server.output, map.output);
  const testing::CommandResult version =
      RunCommand((Prefix() / "bin/objmap").string() + " --version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.output.find("gRPC server and client:  yes"), std::string::npos)
      << version.output;
#endif
}

TEST_F(Install, InstalledServerServesTheInstalledViewerFromAnyDirectory) {
  ASSERT_EQ(install_.exit_code, 0) << install_.output;
  const fs::path web = fs::path(OBJMAP_SOURCE_DIR) / "server/http_viewer/web";
  if (!fs::is_regular_file(web / "node_modules/three/build/three.module.js")) {
    GTEST_SKIP() << "SKIPPED: three.js is not installed in " << web
                 << "/node_modules (scripts/setup.sh), so the install has no viewer";
  }
  const fs::path viewer = Prefix() / "share/objmap/viewer";
  for (const std::string& file : http_viewer::ViewerFiles()) {
    EXPECT_EQ(ReadText(viewer / file), ReadText(web / file)) << file;
  }
#ifndef OBJMAP_TEST_WITH_SERVER
  GTEST_SKIP() << "SKIPPED: needs objmap_server (a build with OBJMAP_WITH_GRPC=ON)";
#else
  // Started elsewhere, the installed server finds the installed page, not the source tree's.
  const TempFolder elsewhere("install_viewer");
  const std::string log = (elsewhere.path() / "server.log").string();
  const testing::CommandResult started = RunCommand(
      "cd '" + elsewhere.path().string() + "' && '" + (Prefix() / "bin/objmap_server").string() +
      "' --db map.db --no-detector --listen 127.0.0.1:0 --http 127.0.0.1:0 > '" + log +
      "' 2>&1 & echo $!");
  const pid_t pid = std::stoi(started.output);
  std::string printed;
  for (int i = 0; i < 300 && printed.find("listening on") == std::string::npos; ++i) {
    usleep(50000);
    printed = ReadText(log);
  }
  kill(pid, SIGTERM);
  EXPECT_NE(printed.find("objmap_server viewer at http://127.0.0.1:"), std::string::npos) << printed;
  // Without its files, the viewer does not start and the server says where it looked.
  fs::rename(viewer, viewer.string() + ".moved");
  const testing::CommandResult missing = RunCommand(
      "cd '" + elsewhere.path().string() + "' && '" + (Prefix() / "bin/objmap_server").string() +
      "' --db map2.db --no-detector --listen 127.0.0.1:0 --http 127.0.0.1:0");
  fs::rename(viewer.string() + ".moved", viewer);
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("next to the executable: " + viewer.string()), std::string::npos)
      << missing.output;
  EXPECT_EQ(missing.output.find("source tree"), std::string::npos) << missing.output;
#endif
}

// --print-config, edit, read back: the map reflects the edited resolution; objmap_server reads and
// prints the same file alike; flags win over the file; unknown keys are refused by name.
TEST(ConfigFile, PrintEditReadBackAndMap) {
  const TempFolder folder("config_round_trip");
  const std::string objmap = OBJMAP_CLI_PATH;
  const testing::CommandResult printed = RunCommand(objmap + " map --print-config");
  ASSERT_EQ(printed.exit_code, 0) << printed.output;
  const std::string defaults = printed.output;
  ASSERT_NE(defaults.find("resolution_m: 0.01\n"), std::string::npos) << defaults;

  std::string edited = defaults;
  edited.replace(edited.find("resolution_m: 0.01\n"), 19, "resolution_m: 0.02\n");
  const fs::path config = folder.path() / "objmap.yaml";
  std::ofstream(config) << edited;
  const testing::CommandResult read_back =
      RunCommand(objmap + " map --print-config --config '" + config.string() + "'");
  ASSERT_EQ(read_back.exit_code, 0) << read_back.output;
  EXPECT_EQ(read_back.output, edited);
#ifdef OBJMAP_TEST_WITH_SERVER
  const testing::CommandResult server = RunCommand(
      std::string(OBJMAP_SERVER_PATH) + " --print-config --config '" + config.string() + "'");
  ASSERT_EQ(server.exit_code, 0) << server.output;
  EXPECT_EQ(server.output, edited);
#endif

  // Flags and --set win over the file.
  const testing::CommandResult flags = RunCommand(
      objmap + " map --print-config --config '" + config.string() +
      "' --min-observations 7 --set association.match_distance_m=0.03 --every-nth-frame 4");
  ASSERT_EQ(flags.exit_code, 0) << flags.output;
  EXPECT_NE(flags.output.find("min_observations: 7\n"), std::string::npos) << flags.output;
  EXPECT_NE(flags.output.find("match_distance_m: 0.03\n"), std::string::npos) << flags.output;
  EXPECT_NE(flags.output.find("every_nth_frame: 4\n"), std::string::npos) << flags.output;
  EXPECT_NE(flags.output.find("resolution_m: 0.02\n"), std::string::npos) << flags.output;

  // Unknown and mistyped keys are refused by name, from the file and from --set.
  std::string misspelt = edited;
  misspelt.replace(misspelt.find("resolution_m: 0.02"), 12, "resolution");
  const fs::path bad = folder.path() / "bad.yaml";
  std::ofstream(bad) << misspelt;
  const testing::CommandResult unknown =
      RunCommand(objmap + " map --print-config --config '" + bad.string() + "'");
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.output.find(bad.string() + ": occupancy.resolution: unknown key"),
            std::string::npos)
      << unknown.output;
  const testing::CommandResult bad_set =
      RunCommand(objmap + " map --print-config --set occupancy.resolution_m=fine");
  EXPECT_EQ(bad_set.exit_code, 1);
  EXPECT_NE(bad_set.output.find("occupancy.resolution_m: expected a number, got 'fine'"),
            std::string::npos)
      << bad_set.output;

  if (!testing::Exists(Redkitchen()) || !fs::is_regular_file(kModel)) {
    GTEST_SKIP() << "SKIPPED: needs ../shared/data/redkitchen and the detector model " << kModel
                 << " to map with the edited file";
  }
  const testing::CommandResult map =
      RunCommand(objmap + " map '" + Redkitchen() + "' --out '" + (folder.path() / "out").string() +
                 "' --max-frames 4 --every-nth-frame 2 --config '" + config.string() + "'");
  ASSERT_EQ(map.exit_code, 0) << map.output;
  EXPECT_DOUBLE_EQ(BtResolution(folder.path() / "out/map.bt"), 0.02);
  const testing::CommandResult map_default =
      RunCommand(objmap + " map '" + Redkitchen() + "' --out '" +
                 (folder.path() / "out_default").string() + "' --max-frames 4 --every-nth-frame 2");
  ASSERT_EQ(map_default.exit_code, 0) << map_default.output;
  EXPECT_DOUBLE_EQ(BtResolution(folder.path() / "out_default/map.bt"), 0.01);
}

TEST(Help, EveryCommandSaysWhatItDoesFirst) {
  const std::string objmap = OBJMAP_CLI_PATH;
  const testing::CommandResult top = RunCommand(objmap + " --help");
  EXPECT_EQ(top.exit_code, 0);
  EXPECT_EQ(top.output.rfind("objmap: ", 0), 0u) << top.output;
  std::vector<std::string> commands = {"map", "segment", "eval"};
#ifdef OBJMAP_TEST_WITH_SERVER
  for (const char* name : {"ingest", "inventory", "objects", "free", "export", "update-poses",
                           "keyframes", "status"}) {
    commands.push_back(name);
  }
#endif
  for (const std::string& command : commands) {
    const testing::CommandResult help = RunCommand(objmap + " " + command + " --help");
    EXPECT_EQ(help.exit_code, 0) << command << ": " << help.output;
    EXPECT_EQ(help.output.rfind("objmap " + command + ": ", 0), 0u) << help.output;
    EXPECT_NE(help.output.find("usage: objmap " + command), std::string::npos) << help.output;
  }
  const testing::CommandResult version = RunCommand(objmap + " --version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_TRUE(std::regex_search(version.output, std::regex(R"(^objmap \d+\.\d+\.\d+\n)")))
      << version.output;
  for (const char* part : {"gRPC", "ROS1", "OpenNI2"}) {
    EXPECT_NE(version.output.find(part), std::string::npos) << part << ": " << version.output;
  }
}

}  // namespace
}  // namespace objmap
