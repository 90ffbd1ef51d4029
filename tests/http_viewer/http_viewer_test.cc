// The web viewer's HTTP side against a real MapServer (SQLite file) and a real map folder
// (written by WriteMapOutputs), through cpp-httplib's client and raw sockets on 127.0.0.1.
#include "http_viewer/http_viewer.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <set>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "http_viewer/viewer_map.h"
#include "mapper/map_export.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap::http_viewer {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::SceneBox;

const int kCup = CocoClassId("cup");
const std::string kViewerFolder = OBJMAP_VIEWER_DIR;

// A table top with two cups and a wall behind, seen from three viewpoints (as map_server_test).
class ViewerScene : public ::testing::Test {
 protected:
  ViewerScene() {
    boxes_ = {
        {{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},      // table top
        {{-0.05, -0.25, 0.70}, {0.05, -0.15, 0.82}, {200, 30, 30}},  // cup 1, red
        {{-0.05, 0.15, 0.70}, {0.05, 0.25, 0.82}, {30, 30, 200}},    // cup 2, blue
        {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}},        // wall
    };
    eyes_ = {{-1.0, 0.0, 1.3}, {-1.0, 0.25, 1.3}, {-0.95, -0.25, 1.35}};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) /
           ("objmap_http_viewer_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~ViewerScene() override {
    viewer_.reset();
    server_.reset();
    fs::remove_all(dir_);
  }

  void SetUp() override {
    std::string why;
    if (!FindViewerFolder(kViewerFolder, &folder_, &why)) {
      GTEST_SKIP() << "SKIPPED: " << why;
    }
  }

  Eigen::Isometry3d Pose(int view) const {
    return testing::LookAt(eyes_[view], Eigen::Vector3d(0, 0, 0.7));
  }
  RgbdFrame Frame(int view) const {
    return testing::RenderFrame(boxes_, K_, Pose(view), "view-" + std::to_string(view));
  }
  std::vector<Detection> CupDetections(int view) const {
    return {{testing::ProjectBox(boxes_[1], Pose(view), K_), kCup, 0.6f},
            {testing::ProjectBox(boxes_[2], Pose(view), K_), kCup, 0.5f}};
  }

  // A MapServer with the three views, and the viewer on it on a free loopback port.
  void StartLiveViewer() {
    std::string why;
    server_ = MapServer::Open(MapServerConfig(), (dir_ / "map.db").string(), nullptr, &why);
    ASSERT_TRUE(server_) << why;
    for (int view = 0; view < 3; ++view) {
      AddKeyframeOutcome outcome;
      const ServiceStatus status = server_->AddKeyframe(Frame(view), CupDetections(view), &outcome);
      ASSERT_TRUE(status.ok()) << status.message;
    }
    live_ = std::make_unique<LiveViewerMap>(*server_, "test server");
    StartViewer(*live_);
  }

  void StartViewer(const ViewerMap& map) {
    HttpViewerConfig config;
    config.listen_address = "127.0.0.1:0";
    config.viewer_folder = folder_;
    std::string why;
    viewer_ = HttpViewer::Start(config, map, &why);
    ASSERT_TRUE(viewer_) << why;
    client_ = std::make_unique<httplib::Client>("127.0.0.1", viewer_->port());
    client_->set_read_timeout(30, 0);
  }

  httplib::Result Get(const std::string& path) { return client_->Get(path.c_str()); }
  json GetJson(const std::string& path, int expected_status = 200) {
    auto result = Get(path);
    EXPECT_TRUE(result) << path;
    if (!result) return json();
    EXPECT_EQ(result->status, expected_status) << path << ": " << result->body;
    EXPECT_EQ(result->get_header_value("Content-Type"), "application/json") << path;
    return json::parse(result->body, nullptr, false);
  }

  // The raw answer to a request line sent as is (no client-side path normalisation).
  std::string RawRequest(const std::string& target, const std::string& host = "127.0.0.1") const {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(viewer_->port()));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
    const std::string request =
        "GET " + target + " HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n\r\n";
    EXPECT_EQ(send(fd, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
    std::string answer;
    char buffer[65536];
    for (ssize_t n; (n = recv(fd, buffer, sizeof(buffer), 0)) > 0;) answer.append(buffer, n);
    close(fd);
    return answer;
  }

  CameraIntrinsics K_;
  std::vector<SceneBox> boxes_;
  std::vector<Eigen::Vector3d> eyes_;
  fs::path dir_;
  std::string folder_;
  std::unique_ptr<MapServer> server_;
  std::unique_ptr<LiveViewerMap> live_;
  std::unique_ptr<HttpViewer> viewer_;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(ViewerScene, TheMapAnswerIsTheServersInventoryAndObjects) {
  StartLiveViewer();
  const json map = GetJson("/api/map");
  std::vector<InventoryEntry> inventory;
  std::uint64_t version = 0;
  ASSERT_TRUE(server_->Inventory(std::nullopt, &inventory, &version).ok());
  EXPECT_EQ(map["version"], version);
  EXPECT_EQ(map["keyframes"], 3);
  ASSERT_EQ(map["inventory"].size(), inventory.size());
  for (std::size_t i = 0; i < inventory.size(); ++i) {
    EXPECT_EQ(map["inventory"][i]["class"], std::string(ObjectClassName(inventory[i].class_id)));
    EXPECT_EQ(map["inventory"][i]["count"], inventory[i].count);
    EXPECT_EQ(map["inventory"][i]["objects"].get<std::vector<ObjectId>>(), inventory[i].objects);
  }
  ASSERT_EQ(inventory.size(), 1u);
  EXPECT_EQ(inventory[0].count, 2);
  const auto snapshot = server_->Snapshot();
  ASSERT_EQ(map["objects"].size(), snapshot->objects.size());
  std::set<ObjectId> counted(inventory[0].objects.begin(), inventory[0].objects.end());
  for (const json& object : map["objects"]) {
    const auto& view = *snapshot->objects.at(object["id"].get<ObjectId>());
    EXPECT_EQ(object["class"], std::string(ObjectClassName(view.class_id)));
    EXPECT_EQ(object["in_inventory"], counted.count(view.id) > 0);
    EXPECT_EQ(object["confirmed"], view.confirmed);
    EXPECT_EQ(object["observations"], view.observations);
    EXPECT_NEAR(object["centroid"][2].get<float>(), view.centroid_W.z(), 1e-5);
    EXPECT_EQ(object["colour"].get<std::string>().size(), 7u);
  }
  // The cameras look down at the table from above it: up is about +z (three headings close
  // together tell it only roughly).
  ASSERT_TRUE(map["up"].is_array());
  EXPECT_GT(map["up"][2].get<double>(), 0.8);
}

TEST_F(ViewerScene, ARemovedCupIsAGhostWithItsChange) {
  StartLiveViewer();
  ObjectId red_cup = 0;  // the cup at y = -0.2
  for (const auto& [id, view] : server_->Snapshot()->objects) {
    if (view->centroid_W.y() < 0.f) red_cup = id;
  }
  ASSERT_NE(red_cup, 0);
  // A second visit from other places: the red cup is gone, the blue one still there.
  std::vector<SceneBox> without_red = {boxes_[0], boxes_[2], boxes_[3]};
  for (const Eigen::Vector3d& eye : testing::table_visits::kSecondEyes) {
    const Eigen::Isometry3d pose = testing::LookAt(eye, testing::table_visits::kTarget);
    AddKeyframeOutcome outcome;
    const std::vector<Detection> blue = {{testing::ProjectBox(boxes_[2], pose, K_), kCup, 0.5f}};
    ASSERT_TRUE(server_->AddKeyframe(testing::RenderFrame(without_red, K_, pose, "revisit"), blue,
                                     &outcome)
                    .ok());
  }
  const auto snapshot = server_->Snapshot();
  ASSERT_EQ(snapshot->tombstones.size(), 1u);
  const ObjectId removed = snapshot->tombstones.begin()->first;
  EXPECT_EQ(removed, red_cup);
  const json map = GetJson("/api/map");
  ASSERT_EQ(map["tombstones"].size(), 1u);
  EXPECT_EQ(map["tombstones"][0]["id"], removed);
  EXPECT_EQ(map["tombstones"][0]["state"], "removed");
  EXPECT_EQ(map["tombstones"][0]["removed"]["keyframe"], 5);
  for (const json& object : map["objects"]) EXPECT_NE(object["id"], removed);
  ASSERT_EQ(map["changes"].size(), 1u);
  EXPECT_EQ(map["changes"][0]["kind"], "removed");
  EXPECT_EQ(map["changes"][0]["id"], removed);
  EXPECT_EQ(map["sessions"], json::array({1}));
  // Its details are still there, for a click on its ghost.
  const json detail = GetJson("/api/objects/" + std::to_string(removed));
  EXPECT_EQ(detail["state"], "removed");
}

TEST_F(ViewerScene, AnObjectComesWithScoresSightingsAModelAndCrops) {
  StartLiveViewer();
  const auto snapshot = server_->Snapshot();
  const ObjectView& cup = *snapshot->objects.begin()->second;
  const json detail = GetJson("/api/objects/" + std::to_string(cup.id));
  EXPECT_EQ(detail["class"], "cup");
  ASSERT_FALSE(detail["scores"].empty());
  EXPECT_EQ(detail["scores"][0]["class"], "cup");
  EXPECT_NEAR(detail["scores"][0]["score"].get<float>(), cup.scores[0].second, 1e-5);
  ASSERT_EQ(detail["sightings"].size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(detail["sightings"][k]["keyframe"], k + 1);
    EXPECT_EQ(detail["sightings"][k]["class"], "cup");
  }

  // The model: float32 x y z per point, then r g b, the 5 mm model point for point.
  auto model = Get("/api/objects/" + std::to_string(cup.id) + "/model");
  ASSERT_TRUE(model);
  ASSERT_EQ(model->status, 200);
  ASSERT_EQ(model->body.size(), cup.model_W->size() * 15);
  float first[3];
  std::memcpy(first, model->body.data(), sizeof(first));
  EXPECT_EQ(Eigen::Vector3f(first[0], first[1], first[2]), cup.model_W->points[0]);
  const std::size_t colours = cup.model_W->size() * 12;
  EXPECT_EQ(static_cast<std::uint8_t>(model->body[colours]), cup.model_W->colors[0][0]);

  // A crop: the keyframe's colour around the box, holding the cup's own colour.
  auto crop = Get(detail["sightings"][1]["image"].get<std::string>());
  ASSERT_TRUE(crop);
  ASSERT_EQ(crop->status, 200) << crop->body;
  EXPECT_EQ(crop->get_header_value("Content-Type"), "image/jpeg");
  const cv::Mat image = cv::imdecode(std::vector<std::uint8_t>(crop->body.begin(), crop->body.end()),
                                     cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_LE(std::max(image.cols, image.rows), 320);
  const cv::Vec3b cup_bgr = cup.model_W->colors[0][0] > 100 ? cv::Vec3b(30, 30, 200)
                                                            : cv::Vec3b(200, 30, 30);
  int cup_pixels = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (cv::norm(image.at<cv::Vec3b>(y, x), cup_bgr) < 60) ++cup_pixels;
    }
  }
  EXPECT_GT(cup_pixels, image.total() / 20) << "the crop does not show the cup";
}

TEST_F(ViewerScene, StructureIsTheOccupiedVoxelsThinnedToTheAskedCount) {
  StartLiveViewer();
  std::vector<Eigen::Vector3d> centers;
  std::uint64_t version = 0;
  ASSERT_TRUE(server_->OccupiedCenters(100000000, &centers, &version).ok());
  ASSERT_GT(centers.size(), 1000u);
  auto all = Get("/api/structure?max_points=" + std::to_string(centers.size()));
  ASSERT_TRUE(all);
  ASSERT_EQ(all->status, 200);
  EXPECT_EQ(all->body.size(), centers.size() * 12);
  EXPECT_EQ(all->get_header_value("X-Objmap-Voxel-Size"), std::to_string(0.01));
  float last[3];
  std::memcpy(last, all->body.data() + all->body.size() - 12, sizeof(last));
  EXPECT_LT((Eigen::Vector3f(last[0], last[1], last[2]) - centers.back().cast<float>()).norm(), 1e-6);
  auto thinned = Get("/api/structure?max_points=500");
  ASSERT_TRUE(thinned);
  EXPECT_LE(thinned->body.size(), 500u * 12);
  EXPECT_GT(thinned->body.size(), 250u * 12);
}

TEST_F(ViewerScene, TheChangeFeedWakesWhenAKeyframeArrives) {
  StartLiveViewer();
  const std::uint64_t version = server_->Snapshot()->version;
  // Nothing new: the poll answers empty after its timeout.
  const json idle = GetJson("/api/changes?since=" + std::to_string(version) + "&timeout_ms=200");
  EXPECT_TRUE(idle["changes"].empty());
  EXPECT_EQ(idle["version"], version);

  auto poll = std::async(std::launch::async, [&] {
    httplib::Client client("127.0.0.1", viewer_->port());
    client.set_read_timeout(30, 0);
    return client.Get(("/api/changes?since=" + std::to_string(version) + "&timeout_ms=20000").c_str());
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  RgbdFrame frame = Frame(1);
  frame.name = "again";
  AddKeyframeOutcome outcome;
  ASSERT_TRUE(server_->AddKeyframe(frame, CupDetections(1), &outcome).ok());
  ASSERT_EQ(poll.wait_for(std::chrono::seconds(10)), std::future_status::ready);
  auto result = poll.get();
  ASSERT_TRUE(result);
  const json feed = json::parse(result->body);
  ASSERT_FALSE(feed["changes"].empty()) << result->body;
  EXPECT_EQ(feed["changes"][0]["kind"], "keyframe_added");
  EXPECT_EQ(feed["changes"][0]["keyframe"], outcome.keyframe_id);
  EXPECT_GE(feed["version"], outcome.map_version);
}

TEST_F(ViewerScene, ManyFollowersNeverStarveTheOtherRequests) {
  StartLiveViewer();
  const std::string since = std::to_string(server_->Snapshot()->version);
  // Half the request threads may wait in long polls; the ones beyond are told to come back later.
  const int waiting = HttpViewerConfig().threads / 2;
  const int extra = 3;
  std::vector<std::future<std::pair<int, std::string>>> polls;
  for (int i = 0; i < waiting + extra; ++i) {
    polls.push_back(std::async(std::launch::async, [&] {
      httplib::Client client("127.0.0.1", viewer_->port());
      client.set_read_timeout(30, 0);
      auto result = client.Get(("/api/changes?since=" + since + "&timeout_ms=6000").c_str());
      return result ? std::make_pair(result->status, result->body) : std::make_pair(0, std::string());
    }));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  // Meanwhile the map and IsFree answer at once.
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(GetJson("/api/map")["keyframes"], 3);
  EXPECT_EQ(GetJson("/api/is_free?min=0,0,1&max=0.1,0.1,1.1")["version"], server_->Snapshot()->version);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
  int answered = 0, refused = 0;
  for (auto& poll : polls) {
    const auto [status, body] = poll.get();
    if (status == 200) ++answered;
    if (status == 503) {
      ++refused;
      EXPECT_NE(body.find("retry"), std::string::npos) << body;
    }
  }
  EXPECT_EQ(answered, waiting);
  EXPECT_EQ(refused, extra);
  // Once they are answered, following is possible again.
  EXPECT_TRUE(GetJson("/api/changes?since=" + since + "&timeout_ms=10")["changes"].empty());
}

TEST_F(ViewerScene, IsFreeAgreesWithTheServer) {
  StartLiveViewer();
  const ObjectView& cup = *server_->Snapshot()->objects.begin()->second;
  struct Box {
    Eigen::Vector3d min, max;
  };
  const std::vector<Box> boxes = {
      {cup.min_W.cast<double>(), cup.max_W.cast<double>()},                   // the cup
      {Eigen::Vector3d(-0.3, -0.1, 0.95), Eigen::Vector3d(-0.2, 0.0, 1.05)},  // air above the table
  };
  int free_boxes = 0;
  for (const Box& box : boxes) {
    for (const bool unknown_is_free : {false, true}) {
      bool expected_free = false;
      RegionOccupancy counts;
      std::vector<ObjectId> inside;
      std::uint64_t version = 0;
      ASSERT_TRUE(
          server_->IsFree(box.min, box.max, unknown_is_free, &expected_free, &counts, &inside, &version)
              .ok());
      char query[256];
      std::snprintf(query, sizeof(query), "/api/is_free?min=%.17g,%.17g,%.17g&max=%.17g,%.17g,%.17g%s",
                    box.min.x(), box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z(),
                    unknown_is_free ? "&unknown_is_free=true" : "");
      const json answer = GetJson(query);
      EXPECT_EQ(answer["free"], expected_free) << query;
      EXPECT_EQ(answer["occupied"], counts.occupied) << query;
      EXPECT_EQ(answer["objects_inside"].get<std::vector<ObjectId>>(), inside) << query;
      free_boxes += expected_free;
    }
  }
  // The cup's box is never free; the air is free at least when unknown counts as free.
  EXPECT_GE(free_boxes, 1);
  EXPECT_LE(free_boxes, 2);
}

TEST_F(ViewerScene, BadRequestsAnswer400Or404WithTheReason) {
  StartLiveViewer();
  struct Case {
    std::string path;
    int status;
    std::string names;  // what the message must mention
  };
  const std::vector<Case> cases = {
      {"/api/nothing", 404, "no such API path"},
      {"/api/objects/999", 404, "object 999 is not in the map"},
      {"/api/objects/cup", 400, "object id"},
      {"/api/objects/-3", 400, "object id"},
      {"/api/objects/1/sightings/77.jpg", 404, "not seen in keyframe 77"},
      {"/api/objects/1/sightings/x.jpg", 400, "keyframe id"},
      {"/api/objects/1/model?points=all", 400, "unknown parameter 'points'"},
      {"/api/structure?max_points=0", 400, "max_points"},
      {"/api/structure?max_points=lots", 400, "max_points"},
      {"/api/structure?max_points=10&max_points=20", 400, "given twice"},
      {"/api/changes", 400, "since"},
      {"/api/changes?since=0&timeout_ms=999999999", 400, "timeout_ms"},
      {"/api/changes?since=-1", 400, "since"},
      {"/api/is_free?min=0,0,0", 400, "min and max"},
      {"/api/is_free?min=0,0&max=1,1,1", 400, "min must be three"},
      {"/api/is_free?min=0,0,0&max=1,1,nan", 400, "max must be three finite"},
      {"/api/is_free?min=1,1,1&max=0,0,0", 400, "min"},
      {"/api/is_free?min=0,0,0&max=1,1,1&unknown_is_free=maybe", 400, "unknown_is_free"},
      {"/api/is_free?min=0,0,0&max=1,1,1&mx=2", 400, "unknown parameter 'mx'"},
      {"/api/is_free?min=-100,-100,-100&max=100,100,100", 400, "m^3"},
  };
  for (const Case& c : cases) {
    const json answer = GetJson(c.path, c.status);
    ASSERT_TRUE(answer.is_object() && answer.contains("error")) << c.path;
    EXPECT_NE(answer["error"].get<std::string>().find(c.names), std::string::npos)
        << c.path << ": " << answer["error"];
  }
  // The server still answers.
  EXPECT_EQ(GetJson("/api/map")["keyframes"], 3);
}

TEST_F(ViewerScene, OnlyTheViewersOwnFilesAreServed) {
  StartLiveViewer();
  std::ifstream index_file(fs::path(folder_) / "index.html");
  const std::string index((std::istreambuf_iterator<char>(index_file)), {});
  auto page = Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->body, index);
  auto three = Get("/node_modules/three/build/three.module.js");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->status, 200);
  EXPECT_NE(three->get_header_value("Content-Type").find("javascript"), std::string::npos);

  // Files beside and above the viewer folder, however the path is spelt, are never served.
  const std::vector<std::string> attempts = {
      "/../CMakeLists.txt",
      "/../../CMakeLists.txt",
      "/%2e%2e/%2e%2e/CMakeLists.txt",
      "/..%2f..%2fhttp_viewer.cc",
      "/node_modules/three/build/../../../index.html",
      "/node_modules/three/package.json",
      "/package.json",
      "//etc/passwd",
      "/etc/passwd",
      "/index.html/../../http_viewer.cc",
      "/viewer.js%00.html",
      "/./index.html/..",
  };
  for (const std::string& target : attempts) {
    const std::string answer = RawRequest(target);
    EXPECT_TRUE(answer.rfind("HTTP/1.1 404", 0) == 0 || answer.rfind("HTTP/1.1 400", 0) == 0)
        << target << ": " << answer.substr(0, 200);
    EXPECT_EQ(answer.find("cmake_minimum_required"), std::string::npos) << target;
    EXPECT_EQ(answer.find("root:x:0"), std::string::npos) << target;
    EXPECT_EQ(answer.find("\"dependencies\""), std::string::npos) << target;
    EXPECT_EQ(answer.find("namespace objmap"), std::string::npos) << target;
  }
}

TEST_F(ViewerScene, BoundToLoopbackAndRefusingOtherHostNames) {
  EXPECT_EQ(HttpViewerConfig().listen_address.rfind("127.0.0.1:", 0), 0u);
  std::string host, why;
  int port = -1;
  ASSERT_TRUE(ParseListenAddress("8480", &host, &port, &why)) << why;
  EXPECT_EQ(host, "127.0.0.1");
  EXPECT_EQ(port, 8480);
  ASSERT_TRUE(ParseListenAddress("[::1]:0", &host, &port, &why)) << why;
  EXPECT_EQ(host, "::1");
  EXPECT_FALSE(ParseListenAddress("localhost:http", &host, &port, &why));
  EXPECT_NE(why.find("port"), std::string::npos);
  EXPECT_FALSE(ParseListenAddress("127.0.0.1:70000", &host, &port, &why));
  EXPECT_TRUE(IsLoopbackHost("127.0.0.1"));
  EXPECT_TRUE(IsLoopbackHost("localhost"));
  EXPECT_FALSE(IsLoopbackHost("0.0.0.0"));
  EXPECT_FALSE(IsLoopbackHost("192.168.1.10"));

  StartLiveViewer();
  EXPECT_EQ(viewer_->url().rfind("http://127.0.0.1:", 0), 0u);
  // A page of another site that resolves its name to 127.0.0.1 (DNS rebinding) is refused.
  const std::string answer = RawRequest("/api/map", "attacker.example:" + std::to_string(viewer_->port()));
  EXPECT_EQ(answer.rfind("HTTP/1.1 403", 0), 0u) << answer.substr(0, 200);
  EXPECT_EQ(RawRequest("/api/map", "localhost:" + std::to_string(viewer_->port())).rfind("HTTP/1.1 200", 0), 0u);
}

TEST_F(ViewerScene, AMissingViewerFileIsReportedByName) {
  std::string folder, why;
  EXPECT_FALSE(FindViewerFolder(dir_.string(), &folder, &why));
  EXPECT_NE(why.find("index.html"), std::string::npos) << why;
  EXPECT_NE(why.find("setup.sh"), std::string::npos) << why;
}

TEST_F(ViewerScene, AMapFolderIsServedAsObjmapMapWroteIt) {
  Mapper mapper{MapperConfig()};
  for (int view = 0; view < 3; ++view) {
    KeyframeResult result;
    std::string why;
    ASSERT_TRUE(mapper.AddKeyframe(Frame(view), CupDetections(view), &result, &why)) << why;
  }
  const fs::path map_dir = dir_ / "map";
  std::string why;
  ASSERT_TRUE(WriteMapOutputs(mapper, map_dir.string(), &why)) << why;
  // Keyframe 2's colour image, as objmap map writes it; keyframe 1's is absent.
  fs::create_directories(map_dir / "keyframes");
  const RgbdFrame frame = Frame(1);
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(frame.color.height, frame.color.width, CV_8UC3,
                       const_cast<std::uint8_t*>(frame.color.rgb.data())),
               bgr, cv::COLOR_RGB2BGR);
  ASSERT_TRUE(cv::imwrite((map_dir / "keyframes" / "2.jpg").string(), bgr));

  std::unique_ptr<FolderViewerMap> folder = FolderViewerMap::Open(map_dir.string(), &why);
  ASSERT_TRUE(folder) << why;
  StartViewer(*folder);
  const json map = GetJson("/api/map");
  ASSERT_EQ(map["inventory"].size(), 1u);
  EXPECT_EQ(map["inventory"][0]["class"], "cup");
  EXPECT_EQ(map["inventory"][0]["count"], 2);
  EXPECT_EQ(map["keyframes"], 3);
  const ObjectId cup = map["inventory"][0]["objects"][0];
  const json detail = GetJson("/api/objects/" + std::to_string(cup));
  ASSERT_EQ(detail["sightings"].size(), 3u);
  auto model = Get("/api/objects/" + std::to_string(cup) + "/model");
  ASSERT_TRUE(model);
  EXPECT_EQ(model->body.size(), detail["points"].get<std::size_t>() * 15);
  EXPECT_GT(model->body.size(), 0u);
  auto crop = Get("/api/objects/" + std::to_string(cup) + "/sightings/2.jpg");
  ASSERT_TRUE(crop);
  EXPECT_EQ(crop->status, 200);
  const json missing = GetJson("/api/objects/" + std::to_string(cup) + "/sightings/1.jpg", 404);
  EXPECT_NE(missing["error"].get<std::string>().find("keyframes"), std::string::npos);
  // IsFree over the folder's OctoMap and models: the cup's box is not free.
  const json answer = GetJson("/api/is_free?min=-0.06,-0.26,0.69&max=0.06,-0.14,0.83&unknown_is_free=1");
  EXPECT_EQ(answer["free"], false);
  // A folder does not change: the feed answers empty after its timeout.
  EXPECT_TRUE(GetJson("/api/changes?since=1&timeout_ms=100")["changes"].empty());

  // A damaged objects.json is refused with its name.
  std::ofstream(map_dir / "objects.json") << "{\"objects\": [{\"id\": 1";
  EXPECT_FALSE(FolderViewerMap::Open(map_dir.string(), &why));
  EXPECT_NE(why.find("objects.json"), std::string::npos) << why;
  fs::remove(map_dir / "map.bt");
  EXPECT_FALSE(FolderViewerMap::Open(map_dir.string(), &why));
  EXPECT_NE(why.find("map.bt"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap::http_viewer
