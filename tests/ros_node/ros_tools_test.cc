// ROS users' own tools against objmap_node: a real rosmaster, the node with its own detector fed
// recorded redkitchen frames by objmap_dataset_player, then the stock command-line tools
// (rosservice call, rostopic echo, rosmsg/rossrv show, roslaunch --nodes) and the rospy example
// client of docs/examples, each run in a shell that sourced the devel space's setup.bash as the
// docs say, and their printed answers checked against the node's answers over roscpp. The cases
// share the node and run in order. Without the ROS Python tools the binary prints SKIPPED.
#include <gtest/gtest.h>
#include <objmap_msgs/Inventory.h>
#include <objmap_msgs/IsFree.h>
#include <objmap_msgs/QueryObjects.h>
#include <objmap_msgs/Status.h>
#include <ros/ros.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli/run_objmap.h"
#include "ros_node/ros_processes.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::CommandResult;
using testing::RosMaster;
using testing::RunCommand;

constexpr char kNode[] = "/objmap_node";
const std::string kModelPath = std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb";
const std::string kDevelSetup = std::string(OBJMAP_DEVEL_DIR) + "/setup.bash";

std::string ShellQuote(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// `command` as a user types it, in a bash that sourced the devel space's setup.bash; stdin is
// empty (rosservice call reads requests from a stdin that is not a terminal).
std::string InRosShell(const std::string& command) {
  return "bash -c " + ShellQuote("source " + ShellQuote(kDevelSetup) + " && " + command) +
         " < /dev/null";
}

CommandResult RunRosTool(const std::string& command) {
  return RunCommand(InRosShell("timeout 120 " + command));
}

// Every match of `pattern`'s first group in `text`.
std::vector<std::string> AllMatches(const std::string& text, const std::string& pattern) {
  std::vector<std::string> found;
  const std::regex expression(pattern);
  for (auto it = std::sregex_iterator(text.begin(), text.end(), expression);
       it != std::sregex_iterator(); ++it) {
    found.push_back((*it)[1].str());
  }
  return found;
}

std::string LabelOf(const objmap_msgs::Object& object) {
  char confidence[32];
  std::snprintf(confidence, sizeof(confidence), "%.2f", object.confidence);
  return object.class_name + " #" + std::to_string(object.id) + " " + confidence;
}

class RosTools : public ::testing::Test {
 protected:
  struct Shared {
    std::string skip_reason;
    std::string setup_error;
    fs::path dir;
    std::unique_ptr<RosMaster> master;
    std::unique_ptr<ChildProcess> node;
    std::unique_ptr<ChildProcess> change_echo;  // rostopic echo -n 1 ~map_changes, from before
                                                // the first frame
  };
  static Shared& shared() {
    static Shared instance;
    return instance;
  }

  static void SetUpTestSuite() {
    Shared& s = shared();
    const std::string dataset = testing::SharedDataPath("redkitchen");
    s.skip_reason = testing::DatasetAndModelSkipReason(dataset, kModelPath);
    if (!s.skip_reason.empty()) return;
    // The tools are Debian's python3-rosservice, python3-rostopic, python3-rosmsg and rospy; a
    // machine without them skips. objmap_msgs for Python is objmap's own build: its absence is
    // a failure, checked in the first case.
    const CommandResult tools =
        RunCommand(InRosShell("command -v rosservice rostopic rosmsg rossrv roslaunch && "
                              "/usr/bin/python3 -c 'import rospy'"));
    if (tools.exit_code != 0) {
      s.skip_reason =
          "SKIPPED: needs the ROS Python tools (rosservice, rostopic, rosmsg, roslaunch, rospy: "
          "bash scripts/setup.sh installs them): " +
          tools.output;
      return;
    }
    s.dir = fs::temp_directory_path() / ("objmap_ros_tools_" + std::to_string(getpid()));
    fs::remove_all(s.dir);
    fs::create_directories(s.dir);
    std::string why;
    if (!Setup(dataset, &why)) s.setup_error = why;
  }

  static bool Setup(const std::string& dataset, std::string* why) {
    Shared& s = shared();
    s.master = std::make_unique<RosMaster>(s.dir.string());
    if (!s.master->Start(why)) return false;
    int argc = 0;
    ros::init(argc, nullptr, "objmap_ros_tools_test",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    ros::start();

    s.node = std::make_unique<ChildProcess>(
        std::vector<std::string>{
            OBJMAP_NODE_PATH, "__name:=objmap_node", "_database:=" + (s.dir / "node.db").string(),
            "_detector/model_path:=" + kModelPath, "_sync_max_interval_s:=0.0"},
        (s.dir / "node.log").string());
    if (!s.node->Start(why)) return false;
    if (!ros::service::waitForService(std::string(kNode) + "/status", ros::Duration(300))) {
      *why = "objmap_node did not advertise its services; its log:\n" + s.node->Log();
      return false;
    }

    // rostopic echo of the change feed, subscribed before the first frame: it must print the
    // first change (keyframe 1) and exit.
    s.change_echo = std::make_unique<ChildProcess>(
        std::vector<std::string>{"bash", "-c",
                                 "source " + ShellQuote(kDevelSetup) +
                                     " && exec rostopic echo -n 1 /objmap_node/map_changes"},
        (s.dir / "map_changes_echo.log").string());
    if (!s.change_echo->Start(why)) return false;
    if (!WaitForSubscriber(std::string(kNode) + "/map_changes", why)) return false;

    // 60 recorded frames, every 5th of the first 300; the player waits for the node before
    // each frame.
    ChildProcess player({OBJMAP_PLAYER_PATH, "__name:=objmap_dataset_player",
                         "_dataset:=" + dataset, "_max_frames:=300", "_every_nth_frame:=5",
                         "_rate:=100.0", "_wait_for_node:=/objmap_node/status"},
                        (s.dir / "player.log").string());
    if (!player.Start(why)) return false;
    const int played = player.WaitForExit(std::chrono::seconds(900));
    if (played != 0) {
      const int node_exit = s.node->WaitForExit(std::chrono::milliseconds(0));
      *why =
          "objmap_dataset_player exited with " + std::to_string(played) + ":\n" + player.Log() +
          "\nobjmap_node " +
          (node_exit < 0 ? std::string("still runs") : "exited with " + std::to_string(node_exit)) +
          "; its log:\n" + s.node->Log();
      return false;
    }
    // Every keyframe mapped before the tools ask.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
    while (true) {
      objmap_msgs::Status status;
      if (ros::service::call(std::string(kNode) + "/status", status) &&
          status.response.keyframes == status.response.keyframes_sent &&
          status.response.ingest_queue == 0 && status.response.keyframes > 0) {
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        *why = "objmap_node did not map the played keyframes in time; its log:\n" + s.node->Log();
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return true;
  }

  // Waits until the master lists a subscriber of `topic` (the echo process's).
  static bool WaitForSubscriber(const std::string& topic, std::string* why) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline && shared().change_echo->running()) {
      XmlRpc::XmlRpcValue args, result, payload;
      args[0] = ros::this_node::getName();
      if (ros::master::execute("getSystemState", args, result, payload, true)) {
        XmlRpc::XmlRpcValue& subscribers = payload[1];
        for (int i = 0; i < subscribers.size(); ++i) {
          if (static_cast<std::string>(subscribers[i][0]) == topic &&
              subscribers[i][1].size() > 0) {
            return true;
          }
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    *why = "rostopic echo did not subscribe to " + topic + "; its output:\n" +
           shared().change_echo->Log();
    return false;
  }

  static void TearDownTestSuite() {
    Shared& s = shared();
    if (s.change_echo) s.change_echo->Stop(SIGINT);
    if (s.node) s.node->Stop(SIGINT);
    if (ros::isStarted()) ros::shutdown();
    if (s.master) s.master->Stop();
    if (!s.dir.empty() && !::testing::Test::HasFailure()) fs::remove_all(s.dir);
  }

  void SetUp() override {
    if (!shared().skip_reason.empty()) GTEST_SKIP() << shared().skip_reason;
    ASSERT_TRUE(shared().setup_error.empty()) << shared().setup_error;
  }

  // A service of the node over roscpp. Each call opens a TCP connection of its own, and one that
  // fails to connect (seen once on a freshly installed machine, with the rostopic processes of
  // the other tests coming and going) is tried again: what the tests check is the answer, which
  // carries its own `ok` and `error`.
  template <typename Service>
  static bool CallNode(const std::string& name, Service* service) {
    for (int attempt = 1; attempt <= 3; ++attempt) {
      if (ros::service::call(std::string(kNode) + "/" + name, *service)) return true;
      std::cerr << "call of " << kNode << "/" << name << " failed (attempt " << attempt << ")\n";
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    return false;
  }

  // The node's inventory over roscpp: class name -> count, most frequent first in `order`.
  static std::map<std::string, int> Inventory(std::vector<std::string>* order) {
    objmap_msgs::Inventory inventory;
    EXPECT_TRUE(CallNode("inventory", &inventory));
    EXPECT_TRUE(inventory.response.ok) << inventory.response.error;
    std::map<std::string, int> counts;
    for (const auto& entry : inventory.response.entries) {
      counts[entry.class_name] = entry.count;
      if (order != nullptr) order->push_back(entry.class_name);
    }
    return counts;
  }

  static std::vector<objmap_msgs::Object> Objects(const std::string& class_name) {
    objmap_msgs::QueryObjects query;
    query.request.class_name = class_name;
    EXPECT_TRUE(CallNode("query_objects", &query));
    EXPECT_TRUE(query.response.ok) << query.response.error;
    return query.response.objects;
  }
};

TEST_F(RosTools, ObjmapMessagesAreImportableFromPythonAndKnownToRosmsg) {
  const CommandResult imported = RunRosTool(
      "/usr/bin/python3 -c 'from objmap_msgs.msg import MapChange, Object; "
      "from objmap_msgs.srv import Inventory, QueryObjects, IsFree; print(MapChange._type)'");
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  EXPECT_NE(imported.output.find("objmap_msgs/MapChange"), std::string::npos) << imported.output;

  const CommandResult message = RunRosTool("rosmsg show objmap_msgs/MapChange");
  ASSERT_EQ(message.exit_code, 0) << message.output;
  EXPECT_NE(message.output.find("uint8 KEYFRAME_ADDED=1"), std::string::npos) << message.output;
  const CommandResult service = RunRosTool("rossrv show objmap_msgs/IsFree");
  ASSERT_EQ(service.exit_code, 0) << service.output;
  EXPECT_NE(service.output.find("bool unknown_is_free"), std::string::npos) << service.output;
  EXPECT_NE(service.output.find("int64[] object_ids"), std::string::npos) << service.output;
}

TEST_F(RosTools, RosserviceCallInventoryPrintsTheNodesInventory) {
  const std::map<std::string, int> expected = Inventory(nullptr);
  ASSERT_FALSE(expected.empty()) << "the node's inventory is empty; its log:\n"
                                 << shared().node->Log();
  const CommandResult call = RunRosTool("rosservice call /objmap_node/inventory '{}'");
  ASSERT_EQ(call.exit_code, 0) << call.output;
  EXPECT_NE(call.output.find("ok: True"), std::string::npos) << call.output;
  // Each entry prints class_name, then count.
  const std::regex entry(R"re(class_name: "([^"]+)"\s+count: (\d+))re");
  std::map<std::string, int> printed;
  for (auto it = std::sregex_iterator(call.output.begin(), call.output.end(), entry);
       it != std::sregex_iterator(); ++it) {
    printed[(*it)[1].str()] = std::stoi((*it)[2].str());
  }
  EXPECT_EQ(printed, expected) << call.output;
  std::cout << "rosservice call /objmap_node/inventory: " << printed.size() << " classes\n";
}

TEST_F(RosTools, RosserviceCallQueryObjectsByClassPrintsThoseObjects) {
  std::vector<std::string> classes;
  Inventory(&classes);
  ASSERT_FALSE(classes.empty());
  // The issue's example asks for cups; any class of the inventory does when the map has none.
  const std::string class_name =
      std::find(classes.begin(), classes.end(), "cup") != classes.end() ? "cup" : classes[0];
  std::set<std::string> expected_ids;
  for (const auto& object : Objects(class_name)) expected_ids.insert(std::to_string(object.id));
  ASSERT_FALSE(expected_ids.empty());

  const CommandResult call =
      RunRosTool("rosservice call /objmap_node/query_objects \"{class_name: " + class_name + "}\"");
  ASSERT_EQ(call.exit_code, 0) << call.output;
  // Objects are list items at four spaces; their scores' ids are deeper.
  const std::vector<std::string> ids = AllMatches(call.output, R"re(\n    id: (\d+)\n)re");
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()), expected_ids) << call.output;
  EXPECT_EQ(ids.size(), expected_ids.size()) << call.output;
  const std::vector<std::string> names =
      AllMatches(call.output, R"re(\n    class_name: "([^"]+)"\n)re");
  EXPECT_EQ(names.size(), ids.size()) << call.output;
  for (const std::string& name : names) EXPECT_EQ(name, class_name) << call.output;

  // A refused request prints the node's reason, naming the field.
  const CommandResult refused =
      RunRosTool("rosservice call /objmap_node/query_objects \"{class_name: chiar}\"");
  EXPECT_NE(refused.output.find("ok: False"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("class_name 'chiar'"), std::string::npos) << refused.output;
}

TEST_F(RosTools, RostopicEchoPrintsTheFirstMapChange) {
  ChildProcess& echo = *shared().change_echo;
  const int code = echo.WaitForExit(std::chrono::seconds(60));
  const std::string printed = echo.Log();
  ASSERT_EQ(code, 0) << printed;
  EXPECT_NE(printed.find("map_version: 1\n"), std::string::npos) << printed;
  EXPECT_NE(printed.find("kind: 1\n"), std::string::npos) << printed;  // KEYFRAME_ADDED
  EXPECT_NE(printed.find("keyframe_id: 1\n"), std::string::npos) << printed;
  EXPECT_NE(printed.find("added_objects: ["), std::string::npos) << printed;
  EXPECT_EQ(AllMatches(printed, R"re((---))re").size(), 1u) << "exactly one message: " << printed;
}

TEST_F(RosTools, RostopicEchoOfTheObjectMarkersShowsEachInventoryObjectsLabel) {
  const std::vector<objmap_msgs::Object> objects = Objects("");
  ASSERT_FALSE(objects.empty());
  // ~objects is latched: a late subscriber gets the markers of the current map.
  const CommandResult echo = RunRosTool("rostopic echo -n 1 /objmap_node/objects");
  ASSERT_EQ(echo.exit_code, 0) << echo.output;
  const std::vector<std::string> labels = AllMatches(echo.output, R"re(text: "([^"]+)")re");
  const std::set<std::string> printed(labels.begin(), labels.end());
  for (const auto& object : objects) {
    EXPECT_EQ(printed.count(LabelOf(object)), 1u)
        << "no marker label \"" << LabelOf(object) << "\" in:\n"
        << echo.output.substr(0, 4000);
  }
  std::cout << "rostopic echo /objmap_node/objects: " << labels.size() << " labels, e.g. \""
            << LabelOf(objects[0]) << "\"\n";
}

TEST_F(RosTools, TheRospyExampleClientQueriesByClassAndAsksIsFree) {
  std::vector<std::string> classes;
  Inventory(&classes);
  ASSERT_FALSE(classes.empty());
  const std::string class_name = classes[0];
  const std::vector<objmap_msgs::Object> objects = Objects(class_name);
  ASSERT_FALSE(objects.empty());

  const std::string example = std::string(OBJMAP_SOURCE_DIR) + "/docs/examples/ros_client.py";
  const CommandResult run =
      RunRosTool("/usr/bin/python3 " + ShellQuote(example) + " --class " + ShellQuote(class_name));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> ids = AllMatches(run.output, R"re(\n  object (\d+): )re");
  std::set<std::string> expected_ids;
  for (const auto& object : objects) expected_ids.insert(std::to_string(object.id));
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()), expected_ids) << run.output;

  // Its default box is the first object's bounds: not free, and that object is named.
  objmap_msgs::IsFree is_free;
  is_free.request.region_min = objects[0].bounds_min;
  is_free.request.region_max = objects[0].bounds_max;
  ASSERT_TRUE(CallNode("is_free", &is_free));
  ASSERT_TRUE(is_free.response.ok) << is_free.response.error;
  ASSERT_FALSE(is_free.response.free);
  EXPECT_NE(
      run.output.find(": not free (" + std::to_string(is_free.response.occupied) + " occupied"),
      std::string::npos)
      << run.output;
  const std::vector<std::string> named = AllMatches(run.output, R"re(objects: ([0-9 ]+)\))re");
  ASSERT_EQ(named.size(), 1u) << run.output;
  EXPECT_NE((" " + named[0] + " ").find(" " + std::to_string(objects[0].id) + " "),
            std::string::npos)
      << run.output;

  // A box given on the command line; a reversed one is refused with the node's reason.
  const CommandResult refused = RunRosTool("/usr/bin/python3 " + ShellQuote(example) + " --class " +
                                           ShellQuote(class_name) + " --box 0 0 0 -1 1 1");
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("is_free refused: region.min.x"), std::string::npos)
      << refused.output;
}

// launch/objmap.rviz shows the node's own topics with displays of their types, in the node's
// world frame; rviz:=true on the launch files adds RViz, and only then.
TEST_F(RosTools, TheRvizConfigurationShowsTopicsTheNodePublishes) {
  ros::master::V_TopicInfo topics;
  ASSERT_TRUE(ros::master::getTopics(topics));
  std::map<std::string, std::string> published;
  for (const auto& topic : topics) published[topic.name] = topic.datatype;

  const YAML::Node config = YAML::LoadFile(std::string(OBJMAP_SOURCE_DIR) + "/launch/objmap.rviz");
  const YAML::Node manager = config["Visualization Manager"];
  EXPECT_EQ(manager["Global Options"]["Fixed Frame"].as<std::string>(), "map");
  const std::map<std::string, std::string> type_of_display = {
      {"rviz/MarkerArray", "visualization_msgs/MarkerArray"},
      {"rviz/PointCloud2", "sensor_msgs/PointCloud2"}};
  std::set<std::string> shown;
  bool shows_tf = false;
  for (const YAML::Node& display : manager["Displays"]) {
    const std::string display_class = display["Class"].as<std::string>();
    if (display_class == "rviz/TF") shows_tf = display["Enabled"].as<bool>();
    const YAML::Node topic = display["Topic"] ? display["Topic"] : display["Marker Topic"];
    if (!topic) continue;
    const std::string name = topic.as<std::string>();
    shown.insert(name);
    ASSERT_EQ(published.count(name), 1u) << name << " is not published";
    ASSERT_EQ(type_of_display.count(display_class), 1u) << display_class;
    EXPECT_EQ(published[name], type_of_display.at(display_class)) << name;
  }
  EXPECT_TRUE(shows_tf);
  for (const char* topic :
       {"/objmap_node/objects", "/objmap_node/occupied_cells", "/objmap_node/object_cloud"}) {
    EXPECT_EQ(shown.count(topic), 1u) << topic << " has no display";
  }

  for (const char* launch : {"objmap.launch", "objmap_dataset.launch", "objmap_openni2.launch"}) {
    const std::string path = std::string(OBJMAP_SOURCE_DIR) + "/launch/" + launch;
    const CommandResult with = RunRosTool("roslaunch --nodes " + ShellQuote(path) +
                                          " rviz:=true dataset:=/tmp world_frame:=odom");
    ASSERT_EQ(with.exit_code, 0) << launch << ": " << with.output;
    EXPECT_NE(with.output.find("/objmap_rviz"), std::string::npos) << launch << ": " << with.output;
    const CommandResult without =
        RunRosTool("roslaunch --nodes " + ShellQuote(path) + " dataset:=/tmp");
    ASSERT_EQ(without.exit_code, 0) << launch << ": " << without.output;
    EXPECT_EQ(without.output.find("/objmap_rviz"), std::string::npos) << launch;
    // RViz's fixed frame follows world_frame and its topics follow node_name: the node as
    // roslaunch's own loader reads it (roslaunch --args would also need RViz installed).
    const CommandResult loaded = RunRosTool(
        "/usr/bin/python3 -c " +
        ShellQuote("import sys, roslaunch.config\n"
                   "sys.argv = ['load', 'rviz:=true', 'dataset:=/tmp', 'world_frame:=odom', "
                   "'node_name:=other']\n"
                   "config = roslaunch.config.load_config_default(['" +
                   path +
                   "'], None)\n"
                   "for node in config.nodes:\n"
                   "    if node.package == 'rviz': print(node.args, node.remap_args)\n"));
    ASSERT_EQ(loaded.exit_code, 0) << launch << ": " << loaded.output;
    EXPECT_NE(
        loaded.output.find("-d " + std::string(OBJMAP_SOURCE_DIR) + "/launch/objmap.rviz -f odom"),
        std::string::npos)
        << launch << ": " << loaded.output;
    EXPECT_NE(loaded.output.find("['/objmap_node/objects', '/other/objects']"),
              std::string::npos)
        << launch << ": " << loaded.output;
  }
}

// What docs/ros.md and launch/README.md tell a user to type: the launch file by package name, in
// a shell that sourced the devel space. roslaunch resolves the name by walking the package folder,
// the build trees inside it included (build/, build/no_grpc_tree, build-fuzz): the name must be
// found once. The launched node is fed a few frames by the launched player and answers
// rosservice.
TEST_F(RosTools, RoslaunchByPackageNameStartsTheDatasetLaunch) {
  const fs::path dir = shared().dir;
  const std::string node = "objmap_by_package";
  ChildProcess launch(
      {"bash", "-c",
       "source " + ShellQuote(kDevelSetup) +
           " && exec roslaunch objmap objmap_dataset.launch dataset:=" +
           ShellQuote(testing::SharedDataPath("redkitchen")) + " node_name:=" + node +
           " run_detector:=false max_frames:=20 every_nth_frame:=10 rate:=100 database:=" +
           ShellQuote((dir / "by_package.db").string())},
      (dir / "roslaunch_by_package.log").string());
  std::string why;
  ASSERT_TRUE(launch.Start(&why)) << why;
  const std::regex keyframes_line("\\bkeyframes: ([0-9]+)");
  CommandResult call;
  int keyframes = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  while (keyframes == 0 && launch.running() && std::chrono::steady_clock::now() < deadline) {
    call = RunRosTool("rosservice call /" + node + "/status '{}'");
    std::smatch match;
    if (call.exit_code == 0 && std::regex_search(call.output, match, keyframes_line)) {
      keyframes = std::stoi(match[1].str());
    }
    if (keyframes == 0) std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  const bool was_running = launch.running();
  EXPECT_EQ(launch.Stop(SIGINT), 0) << launch.Log();
  ASSERT_TRUE(was_running) << "roslaunch objmap objmap_dataset.launch ended:\n" << launch.Log();
  EXPECT_GT(keyframes, 0) << "rosservice call /" << node << "/status: " << call.output
                          << "\nroslaunch:\n" << launch.Log();
  EXPECT_EQ(launch.Log().find("multiple files named"), std::string::npos) << launch.Log();
}

}  // namespace
}  // namespace objmap
