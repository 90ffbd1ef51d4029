// Runs the `objmap` executable on a small rendered 7-Scenes folder, as a user would.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <thread>

#include "run_objmap.h"
#include "test_data.h"
#include "test_scenes.h"
#include "render/map_picture.h"
#include "types/coco_classes.h"

// Last: it includes <resolv.h>, whose _res macro breaks Eigen headers included after it.
#include <httplib.h>

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::RunObjmap;
using testing::SceneBox;

std::string PoseText(const Eigen::Isometry3d& T) {
  std::ostringstream text;
  text.precision(12);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) text << T.matrix()(r, c) << (c == 3 ? "\n" : " ");
  }
  return text.str();
}

// A rendered table with two cups, four frames, and a detections file for them.
class CliScene : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("objmap_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "seq");
    const std::vector<SceneBox> boxes = {{{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},
                                         {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},
                                         {{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}},
                                         {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}}};
    const CameraIntrinsics K;
    std::ofstream(Seq("camera-intrinsics.txt")) << "585 0 320\n0 585 240\n0 0 1\n";
    nlohmann::json detections;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Isometry3d T_W_C =
          testing::LookAt({-1.0, -0.2 + 0.15 * i, 1.3}, Eigen::Vector3d(0, 0, 0.7));
      const RgbdFrame frame = testing::RenderFrame(boxes, K, T_W_C, "");
      WriteFrame(i, frame);
      const std::string name = "frame-00000" + std::to_string(i);
      for (int cup = 1; cup <= 2; ++cup) {
        const BoundingBox2D box = testing::ProjectBox(boxes[cup], T_W_C, K);
        detections["frames"][name].push_back({{"box", {box.x_min, box.y_min, box.x_max, box.y_max}},
                                              {"class", "cup"},
                                              {"score", 0.6}});
      }
    }
    std::ofstream(Path("detections.json")) << detections.dump();
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Seq(const std::string& name) const { return (dir_ / "seq" / name).string(); }

  void WriteFrame(int i, const RgbdFrame& frame) const {
    cv::Mat depth(frame.depth.height, frame.depth.width, CV_16UC1);
    cv::Mat color(frame.color.height, frame.color.width, CV_8UC3);
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        const size_t k = static_cast<size_t>(v) * depth.cols + u;
        depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(frame.depth.depth_m[k] * 1000.f);
        color.at<cv::Vec3b>(v, u) = {frame.color.rgb[3 * k + 2], frame.color.rgb[3 * k + 1],
                                     frame.color.rgb[3 * k]};
      }
    }
    const std::string stem = Seq("frame-00000" + std::to_string(i));
    cv::imwrite(stem + ".depth.png", depth);
    cv::imwrite(stem + ".color.png", color);
    std::ofstream(stem + ".pose.txt") << PoseText(frame.T_W_C);
  }

  std::string MapArguments(const std::string& extra) const {
    return "map " + (dir_ / "seq").string() + " --out " + Path("out") + " --detections " +
           Path("detections.json") + " --every-frame --min-observations 3 " + extra;
  }

  fs::path dir_;
};

TEST_F(CliScene, MapsAndWritesEveryOutput) {
  const CommandResult run = RunObjmap(MapArguments(""));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("keyframes: 4 of 4"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("median ms per keyframe"), std::string::npos) << run.output;
  ASSERT_TRUE(fs::exists(Path("out/map.bt")));
  ASSERT_TRUE(fs::exists(Path("out/timings.csv")));
  std::ifstream json_file(Path("out/objects.json"));
  const nlohmann::json objects = nlohmann::json::parse(json_file);
  ASSERT_EQ(objects["inventory"].size(), 1u) << objects.dump(2);
  EXPECT_EQ(objects["inventory"][0]["class"], "cup");
  EXPECT_EQ(objects["inventory"][0]["count"], 2);
  int ply_files = 0;
  for (const auto& entry : fs::directory_iterator(Path("out/objects"))) {
    ply_files += entry.path().extension() == ".ply" ? 1 : 0;
  }
  EXPECT_EQ(ply_files, 2);
}

// Two runs into one map folder: the second is a new session of the same map (its keyframes
// join the first run's objects), and the folder's files are the whole map's. The second run's
// frames see the first's views again: revisit thinning (on by default, revisits_test) would keep
// them as revisits instead of observations, so it is off here.
TEST_F(CliScene, RunsIntoAMapFolderAreSessionsOfOneMap) {
  const std::string common = "map " + (dir_ / "seq").string() + " --map " + Path("folder") +
                             " --detections " + Path("detections.json") +
                             " --every-frame --min-observations 3 --max-frames 2" +
                             " --set thinning.enabled=false";
  CommandResult run = RunObjmap(common);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("a new map in " + Path("folder")), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("session 1: 2 keyframes mapped of 2 frames read"), std::string::npos)
      << run.output;
  std::ifstream first_json(Path("folder/objects.json"));
  // Two views each: below --min-observations 3, nothing is in the inventory yet.
  EXPECT_EQ(nlohmann::json::parse(first_json)["inventory"].size(), 0u);

  run = RunObjmap(common + " --first-frame 2 --session 'second visit'");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("adding to the map in " + Path("folder") + " (2 keyframes, "),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("session 2 \"second visit\", poses request"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("the map: 4 keyframes, "), std::string::npos) << run.output;
  std::ifstream json_file(Path("folder/objects.json"));
  const nlohmann::json objects = nlohmann::json::parse(json_file);
  ASSERT_EQ(objects["inventory"].size(), 1u) << objects.dump(2);
  EXPECT_EQ(objects["inventory"][0]["class"], "cup");
  EXPECT_EQ(objects["inventory"][0]["count"], 2);
  EXPECT_TRUE(fs::exists(Path("folder/map.bt")));
  EXPECT_TRUE(fs::exists(Path("folder/map.db")));
  std::ifstream keyframes(Path("folder/keyframes.txt"));
  std::string line;
  std::vector<std::string> sessions;
  while (std::getline(keyframes, line)) {
    if (line.empty() || line[0] == '#') continue;
    sessions.push_back(line.substr(line.rfind("session")));
  }
  EXPECT_EQ(sessions, (std::vector<std::string>{"session 1", "session 1", "session 2",
                                                "session 2"}));
  for (int id = 1; id <= 4; ++id) {
    EXPECT_TRUE(fs::exists(Path("folder/keyframes/" + std::to_string(id) + ".jpg"))) << id;
  }

  run = RunObjmap(common + " --out " + Path("o"));
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("--out and --map exclude each other"), std::string::npos)
      << run.output;
  run = RunObjmap(common + " --session " + std::string(300, 'x'));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("--session: name: 300 bytes, at most 200"), std::string::npos)
      << run.output;
}

TEST_F(CliScene, BadFramesAreSkippedWithTheirFileNamedOrStopTheRun) {
  std::ofstream(Seq("frame-000001.color.png")) << "not an image";
  std::ofstream(Seq("frame-000002.pose.txt")) << "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  CommandResult run = RunObjmap(MapArguments("--min-observations 2"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("skipped frame 1: " + Seq("frame-000001.color.png")), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("skipped frame 2: " + Seq("frame-000002.pose.txt") + ": pose has NaN"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("keyframes: 2 of 4"), std::string::npos) << run.output;

  run = RunObjmap(MapArguments("--stop-on-error"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("stopped at frame 1"), std::string::npos) << run.output;
}

TEST_F(CliScene, EstimatedPosesOnRealFramesAreScoredAgainstTheDatasets) {
  const std::string redkitchen = testing::SharedDataPath("redkitchen");
  OBJMAP_REQUIRE_PATH(redkitchen);
  std::ofstream(Path("none.json")) << R"({"frames": {}})";
  const CommandResult run =
      RunObjmap("map " + redkitchen + " --out " + Path("est") + " --detections " +
                Path("none.json") + " --max-frames 60 --poses estimate --object-constraints on");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // Without detections there is no object to tie keyframes with: the graph is left as it is.
  EXPECT_NE(run.output.find("object constraints: 0 objects with distant views, 0 view pairs "
                            "aligned, 0 constraints"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("after object constraints: ATE RMSE "), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("poses estimated by RGB-D odometry from the input's first pose (its "
                            "other poses only score them)"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("odometry: 60 frames, 60 tracked, 0 lost"), std::string::npos)
      << run.output;
  const std::size_t ate = run.output.find("after loop closures: ATE RMSE ");
  ASSERT_NE(ate, std::string::npos) << run.output;
  EXPECT_LT(std::stod(run.output.substr(ate + 30)), 0.03) << run.output;
  std::ifstream trajectory(Path("est/trajectory.txt"));
  std::string line;
  int poses = 0;
  std::string first;
  while (std::getline(trajectory, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (poses++ == 0) first = line;
  }
  EXPECT_EQ(poses, 60);
  // The estimate starts at the dataset's first pose: the map shares the dataset's frame.
  std::istringstream first_pose(first);
  double stamp = 0.0, x = 0.0, y = 0.0, z = 0.0;
  first_pose >> stamp >> x >> y >> z;
  std::ifstream pose_file(redkitchen + "/frame-000000.pose.txt");
  double m[12] = {};
  for (double& value : m) pose_file >> value;
  EXPECT_NEAR(x, m[3], 1e-4);
  EXPECT_NEAR(y, m[7], 1e-4);
  EXPECT_NEAR(z, m[11], 1e-4);

  const CommandResult wrong = RunObjmap(MapArguments("--poses gps"));
  EXPECT_EQ(wrong.exit_code, 2) << wrong.output;
  EXPECT_NE(wrong.output.find("--poses must be auto, input or estimate, not gps"), std::string::npos)
      << wrong.output;
  const CommandResult wrong_constraints = RunObjmap(MapArguments("--object-constraints maybe"));
  EXPECT_EQ(wrong_constraints.exit_code, 2) << wrong_constraints.output;
  EXPECT_NE(wrong_constraints.output.find("--object-constraints must be on or off, not maybe"),
            std::string::npos)
      << wrong_constraints.output;
}

TEST_F(CliScene, EmptyOrMissingInputIsAClearError) {
  fs::create_directories(Path("empty"));
  CommandResult run = RunObjmap("map " + Path("empty") + " --out " + Path("o") + " --detections " +
                                Path("detections.json"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("empty sequence"), std::string::npos) << run.output;
  run = RunObjmap("map " + Path("seq") + " --out " + Path("o") + " --detections " +
                  Path("nope.json"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("nope.json"), std::string::npos) << run.output;
  run = RunObjmap("map " + Path("seq") + " --out " + Path("o") + " --max-frames many");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--max-frames expects a number"), std::string::npos) << run.output;
}

// The picture of the mapped scene from the first frame's camera: each inventory cup shows the
// cup colour where its centroid projects, and the legend printed equals objects.json's inventory.
TEST_F(CliScene, RenderShowsEachInventoryObjectInItsClassColour) {
  const CommandResult map = RunObjmap(MapArguments(""));
  ASSERT_EQ(map.exit_code, 0) << map.output;
  std::ifstream keyframes(Path("out/keyframes.txt"));
  int pose_lines = 0;
  for (std::string line; std::getline(keyframes, line);) pose_lines += !line.empty() && line[0] != '#';
  EXPECT_EQ(pose_lines, 4);

  const Eigen::Isometry3d T_W_C =
      testing::LookAt({-1.0, -0.2, 1.3}, Eigen::Vector3d(0, 0, 0.7));
  const Eigen::Quaterniond q(T_W_C.rotation());
  std::ostringstream camera;
  camera.precision(12);
  camera << T_W_C.translation().x() << " " << T_W_C.translation().y() << " "
         << T_W_C.translation().z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w();
  const CommandResult render = RunObjmap("render " + Path("out") + " --out " + Path("view.png") +
                                         " --view camera --camera " + camera.str() +
                                         " --size 640 480 --fov 50");
  ASSERT_EQ(render.exit_code, 0) << render.output;
  const cv::Mat picture = cv::imread(Path("view.png"));
  ASSERT_EQ(picture.cols, 640);
  ASSERT_EQ(picture.rows, 480);

  std::ifstream json_file(Path("out/objects.json"));
  const nlohmann::json objects = nlohmann::json::parse(json_file);
  std::string legend = "legend:";
  for (const auto& entry : objects["inventory"]) {
    legend += " " + entry["class"].get<std::string>() + " " + std::to_string(entry["count"].get<int>()) + ";";
  }
  EXPECT_NE(render.output.find(legend + "\n"), std::string::npos) << legend << "\n" << render.output;

  const double f = 240.0 / std::tan(25.0 * M_PI / 180.0);
  const RgbColour cup = ClassColour("cup");
  int checked = 0;
  for (const auto& object : objects["objects"]) {
    if (!object["in_inventory"].get<bool>()) continue;
    const Eigen::Vector3d centroid(object["centroid"][0].get<double>(), object["centroid"][1].get<double>(),
                                   object["centroid"][2].get<double>());
    const Eigen::Vector3d p = T_W_C.inverse() * centroid;
    ASSERT_GT(p.z(), 0.0);
    const int u = static_cast<int>(std::lround(f * p.x() / p.z() + 320.0));
    const int v = static_cast<int>(std::lround(f * p.y() / p.z() + 240.0));
    ASSERT_TRUE(u >= 0 && v >= 0 && u < 640 && v < 480) << u << " " << v;
    const cv::Vec3b bgr = picture.at<cv::Vec3b>(v, u);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(bgr[2 - c], cup[static_cast<std::size_t>(c)], 12)
          << "object " << object["id"] << " at pixel " << u << "," << v;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 2);

  // A top view of the same map, up given: a picture that is neither blank nor uniform.
  const CommandResult top =
      RunObjmap("render " + Path("out") + " --out " + Path("top.png") + " --view top --up z");
  ASSERT_EQ(top.exit_code, 0) << top.output;
  const cv::Mat top_picture = cv::imread(Path("top.png"));
  ASSERT_FALSE(top_picture.empty());
  cv::Scalar mean, deviation;
  cv::meanStdDev(top_picture, mean, deviation);
  EXPECT_GT(deviation[0] + deviation[1] + deviation[2], 30.0);
}

TEST_F(CliScene, ViewServesTheMapFolderUntilInterrupted) {
  ASSERT_EQ(RunObjmap(MapArguments("")).exit_code, 0);
  // objmap map wrote each keyframe's colour image for the viewer's crops.
  int images = 0;
  for (const auto& entry : fs::directory_iterator(Path("out/keyframes"))) {
    images += entry.path().extension() == ".jpg" ? 1 : 0;
  }
  EXPECT_EQ(images, 4);

  const std::string log = Path("view.log");
  const CommandResult started = testing::RunCommand(std::string(OBJMAP_CLI_PATH) + " view " + Path("out") +
                                           " --http 127.0.0.1:0 > " + log + " 2>&1 & echo $!");
  const pid_t pid = std::stoi(started.output);
  std::string printed;
  std::size_t at = std::string::npos;
  for (int i = 0; i < 200 && at == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::ifstream file(log);
    printed.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    at = printed.find("at http://127.0.0.1:");
  }
  ASSERT_NE(at, std::string::npos) << printed;
  const int port = std::stoi(printed.substr(at + 20));
  httplib::Client client("127.0.0.1", port);
  auto map = client.Get("/api/map");
  ASSERT_TRUE(map);
  ASSERT_EQ(map->status, 200) << map->body;
  const nlohmann::json answer = nlohmann::json::parse(map->body);
  ASSERT_EQ(answer["inventory"].size(), 1u) << map->body;
  EXPECT_EQ(answer["inventory"][0]["class"], "cup");
  EXPECT_EQ(answer["inventory"][0]["count"], 2);
  const int cup = answer["inventory"][0]["objects"][0];
  auto detail = client.Get(("/api/objects/" + std::to_string(cup)).c_str());
  ASSERT_TRUE(detail);
  const nlohmann::json sightings = nlohmann::json::parse(detail->body)["sightings"];
  ASSERT_FALSE(sightings.empty());
  auto crop = client.Get(sightings[0]["image"].get<std::string>().c_str());
  ASSERT_TRUE(crop);
  EXPECT_EQ(crop->status, 200) << crop->body;
  EXPECT_EQ(crop->get_header_value("Content-Type"), "image/jpeg");

  ASSERT_EQ(kill(pid, SIGINT), 0);
  for (int i = 0; i < 100 && printed.find("stopped") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::ifstream file(log);
    printed.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  }
  EXPECT_NE(printed.find("objmap view: stopped"), std::string::npos) << printed;
}

TEST_F(CliScene, ViewRefusesBadInputWithTheReason) {
  CommandResult run = RunObjmap("view " + Path("nothing") + " --http 127.0.0.1:0");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("nothing/map.bt"), std::string::npos) << run.output;
  run = RunObjmap("view " + Path("nothing") + " --http 0.0.0.0:8480");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--insecure"), std::string::npos) << run.output;
  run = RunObjmap("view " + Path("nothing") + " --http 127.0.0.1:port");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--http"), std::string::npos) << run.output;
  run = RunObjmap("view");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("usage: objmap view"), std::string::npos) << run.output;
}

TEST_F(CliScene, RenderRefusesBadInputWithTheReason) {
  CommandResult run = RunObjmap("render " + Path("nothing") + " --out " + Path("x.png"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("map.bt"), std::string::npos) << run.output;
  // A header without its data, and a real map cut short.
  fs::create_directories(Path("corrupt"));
  std::ofstream(Path("corrupt/map.bt")) << "# Octomap OcTree binary file\nid OcTree\nres 0.01\ndata\nxx";
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("corrupt/map.bt: not an OctoMap"), std::string::npos) << run.output;
  ASSERT_EQ(RunObjmap(MapArguments("")).exit_code, 0);
  fs::create_directories(Path("cut"));
  {
    std::ifstream whole(Path("out/map.bt"), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(whole)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 400u);
    std::ofstream(Path("cut/map.bt"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  run = RunObjmap("render " + Path("cut") + " --out " + Path("x.png"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("cut/map.bt"), std::string::npos) << run.output;
  // objects.json that is not JSON.
  fs::copy_file(Path("out/map.bt"), Path("corrupt/map.bt"), fs::copy_options::overwrite_existing);
  std::ofstream(Path("corrupt/objects.json")) << "{\"objects\": [";
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("corrupt/objects.json"), std::string::npos) << run.output;
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png") + " --view sideways");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--view must be"), std::string::npos) << run.output;
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png") + " --view camera");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--camera"), std::string::npos) << run.output;
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png") + " --size 1e12 10");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--size"), std::string::npos) << run.output;
  run = RunObjmap("render " + Path("corrupt") + " --out " + Path("x.png") +
                  " --view top --camera 0 0 0 0 0 0 1");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.output.find("--camera gives the pose of --view camera"), std::string::npos)
      << run.output;
  run = RunObjmap("render " + Path("out") + " --out " + Path("x.png") + " --class giraffe");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("giraffe"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists(Path("x.png")));
}

TEST(CliSegment, WritesOneLabelPerPoint) {
  const std::string cloud = testing::SharedDataPath("mosd-learn/learn0.pcd");
  OBJMAP_REQUIRE_PATH(cloud);
  const std::string out =
      (fs::temp_directory_path() / ("objmap_cli_segment_" + std::to_string(::getpid()) + ".pcd"))
          .string();
  const CommandResult run = RunObjmap("segment " + cloud + " --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("640x480"), std::string::npos) << run.output;
  EXPECT_GT(fs::file_size(out), 640u * 480u * 4u);
  std::ifstream header(out);
  std::string text((std::istreambuf_iterator<char>(header)), {});
  EXPECT_NE(text.find("label"), std::string::npos);
  fs::remove(out);
}

}  // namespace
}  // namespace objmap
