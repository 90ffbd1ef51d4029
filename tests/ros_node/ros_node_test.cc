// objmap_node against a real rosmaster: 52 redkitchen keyframes played as topics + TF into the
// real objmap_node executable (its own CenterNet detector), the same frames sent to the real
// objmap_server over gRPC, then the node's services compared with the server's answers. The
// cases share the node and the server and run in order; the bad-input cases run last.
#include <gtest/gtest.h>
#include <objmap_msgs/GetObject.h>
#include <objmap_msgs/Inventory.h>
#include <objmap_msgs/IsFree.h>
#include <objmap_msgs/MapChange.h>
#include <objmap_msgs/QueryObjects.h>
#include <objmap_msgs/StartSession.h>
#include <objmap_msgs/Status.h>
#include <objmap_msgs/UpdatePoses.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli/run_objmap.h"
#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "integration/server_process.h"
#include "objmap/client.h"
#include "objmap/conversions.h"
#include "ros_conversions.h"
#include "ros_node/ros_processes.h"
#include "rosbag_input/test_bags.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::RosMaster;

constexpr int kKeyframes = 52;
constexpr char kNode[] = "/objmap_node";
constexpr char kCameraFrame[] = "kinect_rgb";
const std::string kModelPath = std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb";

// class name -> number of confirmed objects.
using Counts = std::map<std::string, int>;

std::string Describe(const Counts& counts) {
  std::string text;
  for (const auto& [name, count] : counts) text += name + " " + std::to_string(count) + ", ";
  return text;
}

template <typename Service>
bool Call(const std::string& name, Service* service) {
  return ros::service::call(std::string(kNode) + "/" + name, *service);
}

class RosNode : public ::testing::Test {
 protected:
  struct Shared {
    std::string skip_reason;
    std::string setup_error;
    fs::path dir;
    std::unique_ptr<RosMaster> master;
    std::unique_ptr<ChildProcess> node;
    std::unique_ptr<testing::ServerProcess> grpc_server;
    std::unique_ptr<MapClient> client;
    std::unique_ptr<ros::NodeHandle> handle;
    std::unique_ptr<ros::AsyncSpinner> spinner;
    ros::Publisher color_pub, depth_pub, info_pub, tf_pub;
    ros::ServiceClient status_client;
    std::vector<ros::Subscriber> subscribers;
    std::vector<RgbdFrame> frames;  // the keyframes played, in order
    // What the node published.
    std::mutex published_mutex;
    std::vector<visualization_msgs::MarkerArray> marker_arrays;
    std::vector<objmap_msgs::MapChange> changes;
    std::atomic<int> occupied_clouds{0};
    std::atomic<std::size_t> last_occupied_points{0};
    double next_stamp_s = 100.0;
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
    s.dir = fs::temp_directory_path() / ("objmap_ros_node_" + std::to_string(getpid()));
    fs::remove_all(s.dir);
    fs::create_directories(s.dir);
    std::string why;
    if (!Setup(dataset, &why)) s.setup_error = why;
  }

  static bool Setup(const std::string& dataset, std::string* why) {
    Shared& s = shared();
    if (!ReadKeyframes(dataset, why)) return false;
    s.master = std::make_unique<RosMaster>(s.dir.string());
    if (!s.master->Start(why)) return false;
    int argc = 0;
    ros::init(argc, nullptr, "objmap_ros_node_test",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
    if (!ros::master::check()) {
      *why = "the test cannot reach its rosmaster";
      return false;
    }
    s.handle = std::make_unique<ros::NodeHandle>();
    s.spinner = std::make_unique<ros::AsyncSpinner>(1);
    s.spinner->start();
    Subscribe();

    // The node: its own detector, exact-time pairing (the frames below share one stamp), TF
    // from "map" to the images' frame.
    s.node = std::make_unique<ChildProcess>(
        std::vector<std::string>{OBJMAP_NODE_PATH, "__name:=objmap_node",
                                 "_database:=" + (s.dir / "node.db").string(),
                                 "_detector/model_path:=" + kModelPath, "_sync_max_interval_s:=0.0",
                                 "_publish/occupied_every_keyframes:=10"},
        (s.dir / "node.log").string());
    if (!s.node->Start(why)) return false;
    if (!ros::service::waitForService(std::string(kNode) + "/status", ros::Duration(300))) {
      *why = "objmap_node did not advertise its services; its log:\n" + s.node->Log();
      return false;
    }
    s.color_pub = s.handle->advertise<sensor_msgs::Image>("rgb/image", 5);
    s.depth_pub = s.handle->advertise<sensor_msgs::Image>("depth/image", 5);
    s.info_pub = s.handle->advertise<sensor_msgs::CameraInfo>("rgb/camera_info", 5);
    s.tf_pub = s.handle->advertise<tf2_msgs::TFMessage>("/tf", 100);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (s.color_pub.getNumSubscribers() == 0 || s.depth_pub.getNumSubscribers() == 0 ||
           s.info_pub.getNumSubscribers() == 0 || s.tf_pub.getNumSubscribers() == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        *why = "objmap_node did not subscribe to rgb/image, depth/image, rgb/camera_info and /tf";
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }

    s.grpc_server = std::make_unique<testing::ServerProcess>(
        OBJMAP_SERVER_PATH, (s.dir / "grpc.db").string(), (s.dir / "grpc.log").string(),
        std::vector<std::string>{"--model", kModelPath});
    if (!s.grpc_server->Start(std::chrono::seconds(300), why)) return false;
    MapClientOptions options;
    options.deadline_s = 300.0;
    s.client = std::make_unique<MapClient>(s.grpc_server->address(), options);

    // Both maps are built at once: the gRPC server from a thread, the node from here.
    std::string grpc_error;
    std::thread grpc_ingest([&] {
      for (const RgbdFrame& frame : s.frames) {
        v1::AddKeyframeResponse response;
        const grpc::Status status = s.client->AddKeyframe(frame, nullptr, &response);
        if (!status.ok()) {
          grpc_error = "gRPC AddKeyframe " + frame.name + ": " + status.error_message();
          return;
        }
      }
    });
    bool played = true;
    for (const RgbdFrame& frame : s.frames) {
      if (!PlayAndWait(frame, why)) {
        played = false;
        break;
      }
    }
    grpc_ingest.join();
    if (!played) return false;
    if (!grpc_error.empty()) {
      *why = grpc_error;
      return false;
    }
    return true;
  }

  static void Subscribe() {
    Shared& s = shared();
    s.subscribers.push_back(s.handle->subscribe<visualization_msgs::MarkerArray>(
        std::string(kNode) + "/objects", 10,
        boost::function<void(const visualization_msgs::MarkerArray::ConstPtr&)>(
            [](const visualization_msgs::MarkerArray::ConstPtr& markers) {
              std::lock_guard<std::mutex> lock(shared().published_mutex);
              shared().marker_arrays.push_back(*markers);
            })));
    s.subscribers.push_back(s.handle->subscribe<objmap_msgs::MapChange>(
        std::string(kNode) + "/map_changes", 100,
        boost::function<void(const objmap_msgs::MapChange::ConstPtr&)>(
            [](const objmap_msgs::MapChange::ConstPtr& change) {
              std::lock_guard<std::mutex> lock(shared().published_mutex);
              shared().changes.push_back(*change);
            })));
    s.subscribers.push_back(s.handle->subscribe<sensor_msgs::PointCloud2>(
        std::string(kNode) + "/occupied_cells", 2,
        boost::function<void(const sensor_msgs::PointCloud2::ConstPtr&)>(
            [](const sensor_msgs::PointCloud2::ConstPtr& cloud) {
              ++shared().occupied_clouds;
              shared().last_occupied_points = std::size_t{cloud->width} * cloud->height;
            })));
  }

  static void TearDownTestSuite() {
    Shared& s = shared();
    if (s.node) {
      const int code = s.node->Stop(SIGINT);
      if (code != 0) std::cerr << "objmap_node exited with " << code << "\n";
    }
    if (s.grpc_server) s.grpc_server->Kill(SIGTERM);
    s.client.reset();
    if (s.spinner) s.spinner->stop();
    s.subscribers.clear();
    s.status_client.shutdown();
    s.handle.reset();
    if (ros::isStarted()) ros::shutdown();
    if (s.master) s.master->Stop();
    if (!s.dir.empty() && !::testing::Test::HasFailure()) fs::remove_all(s.dir);
  }

  void SetUp() override {
    if (!shared().skip_reason.empty()) GTEST_SKIP() << shared().skip_reason;
    ASSERT_TRUE(shared().setup_error.empty()) << shared().setup_error;
  }

  // The first kKeyframes keyframes of the sequence by the default keyframe selection; the node
  // (same selection) takes each of them as a keyframe again.
  static bool ReadKeyframes(const std::string& dataset, std::string* why) {
    Shared& s = shared();
    std::unique_ptr<SequenceReader> reader = OpenSequence(dataset, why);
    if (!reader) return false;
    KeyframeSelector selector{KeyframeSelectorConfig{}};
    for (std::size_t index = 0;
         index < reader->size() && static_cast<int>(s.frames.size()) < kKeyframes; ++index) {
      RgbdFrame frame;
      if (!reader->ReadFrame(index, &frame, why)) return false;
      if (selector.IsKeyframe(frame.T_W_C)) s.frames.push_back(std::move(frame));
    }
    if (static_cast<int>(s.frames.size()) < kKeyframes) {
      *why = dataset + " has only " + std::to_string(s.frames.size()) + " keyframes";
      return false;
    }
    return true;
  }

  // Status over one persistent connection: the player polls it between frames, and a new TCP
  // connection per poll would pile up sockets in TIME_WAIT.
  static objmap_msgs::Status::Response NodeStatus() {
    Shared& s = shared();
    objmap_msgs::Status status;
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (!s.status_client.isValid()) {
        s.status_client = s.handle->serviceClient<objmap_msgs::Status>(
            std::string(kNode) + "/status", /*persistent=*/true);
      }
      if (s.status_client.call(status)) return status.response;
      s.status_client.shutdown();
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << "status call failed three times";
    return status.response;
  }

  // Publishes one frame (TF first, then camera info, depth and colour, all with one stamp) and
  // waits until the node has handled it, whatever the outcome. `color_instead` replaces the
  // frame's colour image (bad input).
  static bool PlayAndWait(const RgbdFrame& frame, std::string* why,
                          const sensor_msgs::Image* color_instead = nullptr,
                          const std::string& camera_frame = kCameraFrame,
                          bool send_transform = true) {
    Shared& s = shared();
    const long long handled_before = NodeStatus().frames_received;
    const ros::Time stamp(s.next_stamp_s);
    s.next_stamp_s += 0.2;
    ros_bridge::FrameMessages m = ros_bridge::FrameToMsgs(frame, stamp, "map", camera_frame);
    if (color_instead != nullptr) {
      const std_msgs::Header header = m.color.header;
      m.color = *color_instead;
      m.color.header = header;
    }
    if (send_transform) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(m.T_W_C);
      s.tf_pub.publish(tf);
    }
    s.info_pub.publish(m.camera_info);
    s.depth_pub.publish(m.depth);
    s.color_pub.publish(m.color);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (NodeStatus().frames_received <= handled_before) {
      if (std::chrono::steady_clock::now() > deadline) {
        *why = "objmap_node did not handle " + frame.name + " within 120 s; its log:\n" +
               s.node->Log();
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return true;
  }

  static Counts NodeInventory() {
    objmap_msgs::Inventory inventory;
    EXPECT_TRUE(Call("inventory", &inventory));
    EXPECT_TRUE(inventory.response.ok) << inventory.response.error;
    Counts counts;
    for (const auto& entry : inventory.response.entries) counts[entry.class_name] = entry.count;
    return counts;
  }

  static Counts GrpcInventory() {
    v1::InventoryResponse response;
    EXPECT_TRUE(shared().client->Inventory(v1::InventoryRequest(), &response).ok());
    Counts counts;
    for (const auto& entry : response.entries()) counts[entry.class_name()] = entry.count();
    return counts;
  }

  static std::vector<objmap_msgs::Object> NodeObjects(const std::string& class_name,
                                                      bool include_model = false) {
    objmap_msgs::QueryObjects query;
    query.request.class_name = class_name;
    query.request.include_model = include_model;
    EXPECT_TRUE(Call("query_objects", &query));
    EXPECT_TRUE(query.response.ok) << query.response.error;
    return query.response.objects;
  }

  static std::vector<v1::Object> GrpcObjects(const std::string& class_name) {
    v1::QueryObjectsRequest request;
    request.set_class_name(class_name);
    v1::QueryObjectsResponse response;
    EXPECT_TRUE(shared().client->QueryObjects(request, &response).ok());
    return {response.objects().begin(), response.objects().end()};
  }

  static objmap_msgs::IsFree::Response NodeIsFree(const Eigen::Vector3d& min_W,
                                                  const Eigen::Vector3d& max_W) {
    objmap_msgs::IsFree query;
    query.request.region_min.x = min_W.x();
    query.request.region_min.y = min_W.y();
    query.request.region_min.z = min_W.z();
    query.request.region_max.x = max_W.x();
    query.request.region_max.y = max_W.y();
    query.request.region_max.z = max_W.z();
    EXPECT_TRUE(Call("is_free", &query));
    EXPECT_TRUE(query.response.ok) << query.response.error;
    return query.response;
  }

  static v1::IsFreeResponse GrpcIsFree(const Eigen::Vector3d& min_W, const Eigen::Vector3d& max_W) {
    v1::IsFreeRequest request;
    *request.mutable_region() = BoxToProto(min_W, max_W);
    v1::IsFreeResponse response;
    EXPECT_TRUE(shared().client->IsFree(request, &response).ok());
    return response;
  }
};

TEST_F(RosNode, TakesEveryPlayedKeyframeLikeTheGrpcServer) {
  const objmap_msgs::Status::Response status = NodeStatus();
  EXPECT_EQ(status.frames_received, kKeyframes);
  EXPECT_EQ(status.frames_rejected, 0) << status.last_rejection;
  EXPECT_EQ(status.keyframes_sent, kKeyframes);
  EXPECT_EQ(status.keyframes, kKeyframes);
  v1::StatusResponse grpc_status;
  ASSERT_TRUE(shared().client->Status(v1::StatusRequest(), &grpc_status).ok());
  EXPECT_EQ(grpc_status.keyframes(), kKeyframes);
  EXPECT_EQ(status.objects, grpc_status.objects());
  EXPECT_EQ(status.confirmed_objects, grpc_status.confirmed_objects());
}

TEST_F(RosNode, InventoryIsTheGrpcServers) {
  const Counts node = NodeInventory();
  const Counts grpc = GrpcInventory();
  std::cout << "node inventory: " << Describe(node) << "\ngRPC inventory: " << Describe(grpc)
            << std::endl;
  EXPECT_EQ(node, grpc);
  // The kitchen's table and its mugs are in it.
  EXPECT_EQ(node.count("dining table"), 1u);
  EXPECT_GE(node.count("cup"), 1u);
}

TEST_F(RosNode, ObjectsByClassAreTheGrpcServers) {
  for (const auto& [class_name, count] : GrpcInventory()) {
    const std::vector<objmap_msgs::Object> node = NodeObjects(class_name);
    const std::vector<v1::Object> grpc = GrpcObjects(class_name);
    ASSERT_EQ(node.size(), grpc.size()) << class_name;
    EXPECT_EQ(static_cast<int>(node.size()), count) << class_name;
    for (std::size_t i = 0; i < node.size(); ++i) {
      EXPECT_EQ(node[i].id, grpc[i].id()) << class_name;
      EXPECT_EQ(node[i].class_name, class_name);
      EXPECT_EQ(node[i].observations, grpc[i].observations()) << class_name << " " << node[i].id;
      const Eigen::Vector3d centroid(node[i].centroid.x, node[i].centroid.y, node[i].centroid.z);
      EXPECT_LT((centroid - Vec3FromProto(grpc[i].centroid())).norm(), 0.005)
          << class_name << " " << node[i].id;
      EXPECT_NEAR(node[i].confidence, grpc[i].confidence(), 1e-3);
    }
  }
  // Objects no detection named are asked for as "unknown" on both (and are in no inventory).
  const std::vector<objmap_msgs::Object> node_unknown = NodeObjects("unknown");
  const std::vector<v1::Object> grpc_unknown = GrpcObjects("unknown");
  ASSERT_EQ(node_unknown.size(), grpc_unknown.size());
  for (std::size_t i = 0; i < node_unknown.size(); ++i) {
    EXPECT_EQ(node_unknown[i].id, grpc_unknown[i].id());
    EXPECT_EQ(node_unknown[i].class_name, "unknown");
  }
  std::cout << node_unknown.size() << " unknown object(s)" << std::endl;
  // With the model on request: a PointCloud2 of the 5 mm model.
  const std::vector<objmap_msgs::Object> tables = NodeObjects("dining table", true);
  ASSERT_EQ(tables.size(), 1u);
  EXPECT_GT(tables[0].model.width, 1000u);
  EXPECT_EQ(tables[0].model.data.size(), std::size_t{tables[0].model.width} * 16);
}

TEST_F(RosNode, AirIsFreeAndTheTableTopIsNotAsOverGrpc) {
  // An 8 cm box 60 cm in front of the first keyframe's camera, where its depth image sees far
  // past (redkitchen's first view looks across the kitchen).
  const RgbdFrame& first = shared().frames.front();
  const Eigen::Vector3d centre = first.T_W_C * Eigen::Vector3d(0.0, 0.0, 0.6);
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.04);
  const objmap_msgs::IsFree::Response air = NodeIsFree(centre - half, centre + half);
  EXPECT_TRUE(air.free) << air.occupied << " occupied, " << air.unknown << " unknown";
  EXPECT_EQ(air.free, GrpcIsFree(centre - half, centre + half).free());

  const std::vector<objmap_msgs::Object> tables = NodeObjects("dining table", true);
  ASSERT_EQ(tables.size(), 1u);
  // The model point nearest the table's centroid: on the table top.
  const auto& cloud = tables[0].model;
  const Eigen::Vector3f centroid(tables[0].centroid.x, tables[0].centroid.y, tables[0].centroid.z);
  Eigen::Vector3f on_top = Eigen::Vector3f::Zero();
  float best = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < cloud.width; ++i) {
    Eigen::Vector3f p;
    std::memcpy(p.data(), cloud.data.data() + i * cloud.point_step, 12);
    if ((p - centroid).squaredNorm() < best) {
      best = (p - centroid).squaredNorm();
      on_top = p;
    }
  }
  const Eigen::Vector3d top = on_top.cast<double>();
  const Eigen::Vector3d small = Eigen::Vector3d::Constant(0.03);
  const objmap_msgs::IsFree::Response table_top = NodeIsFree(top - small, top + small);
  EXPECT_FALSE(table_top.free);
  EXPECT_EQ(std::count(table_top.object_ids.begin(), table_top.object_ids.end(), tables[0].id), 1);
  const v1::IsFreeResponse grpc_top = GrpcIsFree(top - small, top + small);
  EXPECT_EQ(table_top.free, grpc_top.free());
  EXPECT_EQ(table_top.occupied, grpc_top.occupied());
  EXPECT_EQ(std::vector<std::int64_t>(table_top.object_ids.begin(), table_top.object_ids.end()),
            std::vector<std::int64_t>(grpc_top.object_ids().begin(), grpc_top.object_ids().end()));
}

TEST_F(RosNode, PublishedMarkersChangesAndOccupiedCells) {
  // The publisher thread follows the map; give it a moment after the last keyframe.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  std::size_t changes = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(shared().published_mutex);
      changes = shared().changes.size();
    }
    if (changes >= static_cast<std::size_t>(kKeyframes)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::lock_guard<std::mutex> lock(shared().published_mutex);
  ASSERT_EQ(changes, static_cast<std::size_t>(kKeyframes));
  for (std::size_t i = 0; i < changes; ++i) {
    EXPECT_EQ(shared().changes[i].kind, objmap_msgs::MapChange::KEYFRAME_ADDED);
    EXPECT_EQ(shared().changes[i].map_version, i + 1);
  }
  ASSERT_FALSE(shared().marker_arrays.empty());
  const visualization_msgs::MarkerArray& last = shared().marker_arrays.back();
  const objmap_msgs::Status::Response status = NodeStatus();
  // DELETEALL, then a box and a label per object.
  ASSERT_EQ(last.markers.size(), 1 + 2 * static_cast<std::size_t>(status.objects));
  EXPECT_EQ(last.markers[0].action, visualization_msgs::Marker::DELETEALL);
  int table_labels = 0;
  for (const visualization_msgs::Marker& marker : last.markers) {
    if (marker.action == visualization_msgs::Marker::DELETEALL) continue;
    EXPECT_EQ(marker.header.frame_id, "map");
    if (marker.type == visualization_msgs::Marker::TEXT_VIEW_FACING) {
      table_labels += marker.text.rfind("dining table", 0) == 0;
    } else {
      EXPECT_EQ(marker.type, visualization_msgs::Marker::CUBE);
      EXPECT_GT(marker.scale.x * marker.scale.y * marker.scale.z, 0.0);
    }
  }
  // Every table the map holds, confirmed or not, has its label.
  objmap_msgs::QueryObjects tables;
  tables.request.class_name = "dining table";
  tables.request.include_unconfirmed = true;
  ASSERT_TRUE(Call("query_objects", &tables));
  EXPECT_GE(table_labels, 1);
  EXPECT_EQ(table_labels, static_cast<int>(tables.response.objects.size()));
  EXPECT_GE(shared().occupied_clouds.load(), kKeyframes / 10);
  EXPECT_GT(shared().last_occupied_points.load(), 10000u);
}

// The played frames written into a bag (the messages the node got, /tf included) map through
// `objmap map` to the node's inventory.
TEST_F(RosNode, ABagOfThePlayedFramesMapsToTheNodesInventory) {
  const fs::path bag = shared().dir / "played.bag";
  testing::WriteTestBag(bag.string(), shared().frames);
  const fs::path out = shared().dir / "bag_map";
  const testing::CommandResult run =
      testing::RunObjmap("map " + bag.string() + " --out " + out.string() + " 2>&1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream file(out / "objects.json");
  const nlohmann::json objects = nlohmann::json::parse(file);
  EXPECT_EQ(objects["keyframes"].get<int>(), kKeyframes);
  Counts counts;
  for (const auto& entry : objects["inventory"]) {
    counts[entry["class"].get<std::string>()] = entry["count"].get<int>();
  }
  std::cout << "objmap map on the bag: " << Describe(counts) << std::endl;
  EXPECT_EQ(counts, NodeInventory());
}

// Bad input after the comparisons: each is answered or logged with its reason, and the node
// keeps serving.
TEST_F(RosNode, MismatchedImageSizesAreRejectedWithTheReason) {
  const objmap_msgs::Status::Response before = NodeStatus();
  RgbdFrame frame = shared().frames.back();
  frame.T_W_C.translation().x() += 1.0;  // far enough to be a keyframe were it valid
  sensor_msgs::Image small = ros_bridge::ColorToMsg(frame.color);
  small.width = 320;
  small.height = 240;
  small.step = 320 * 3;
  small.data.resize(320 * 240 * 3);
  std::string why;
  ASSERT_TRUE(PlayAndWait(frame, &why, &small)) << why;
  const objmap_msgs::Status::Response after = NodeStatus();
  EXPECT_EQ(after.frames_rejected, before.frames_rejected + 1);
  EXPECT_EQ(after.keyframes, before.keyframes);
  EXPECT_NE(after.last_rejection.find("color is 320x240 but depth is 640x480"), std::string::npos)
      << after.last_rejection;
  EXPECT_NE(shared().node->Log().find("color is 320x240 but depth is 640x480"), std::string::npos);
}

TEST_F(RosNode, AFrameWithoutTransformIsRejectedWithTheReason) {
  const objmap_msgs::Status::Response before = NodeStatus();
  std::string why;
  ASSERT_TRUE(PlayAndWait(shared().frames.back(), &why, /*color_instead=*/nullptr,
                          "camera_without_tf", /*send_transform=*/false))
      << why;
  const objmap_msgs::Status::Response after = NodeStatus();
  EXPECT_EQ(after.frames_rejected, before.frames_rejected + 1);
  EXPECT_EQ(after.keyframes, before.keyframes);
  EXPECT_NE(after.last_rejection.find("no transform from 'camera_without_tf' to 'map'"),
            std::string::npos)
      << after.last_rejection;
}

TEST_F(RosNode, UnknownIdsAndBadRequestsGetAnErrorField) {
  objmap_msgs::GetObject get;
  get.request.id = 987654;
  ASSERT_TRUE(Call("get_object", &get));
  EXPECT_FALSE(get.response.ok);
  EXPECT_NE(get.response.error.find("987654"), std::string::npos) << get.response.error;

  objmap_msgs::UpdatePoses update;
  update.request.poses.resize(1);
  update.request.poses[0].keyframe_id = 987654;
  update.request.poses[0].T_W_C.orientation.w = 1.0;
  ASSERT_TRUE(Call("update_poses", &update));
  EXPECT_FALSE(update.response.ok);
  EXPECT_NE(update.response.error.find("987654"), std::string::npos) << update.response.error;

  update.request.poses[0].keyframe_id = 1;
  update.request.poses[0].T_W_C.orientation.w = 0.0;  // not a rotation
  ASSERT_TRUE(Call("update_poses", &update));
  EXPECT_FALSE(update.response.ok);
  EXPECT_NE(update.response.error.find("poses[0].T_W_C.orientation"), std::string::npos)
      << update.response.error;

  objmap_msgs::QueryObjects query;
  query.request.class_name = "unicorn";
  ASSERT_TRUE(Call("query_objects", &query));
  EXPECT_FALSE(query.response.ok);
  EXPECT_NE(query.response.error.find("'unicorn' is neither a COCO class nor \"unknown\""),
            std::string::npos);

  objmap_msgs::IsFree inverted;
  inverted.request.region_min.x = 1.0;
  inverted.request.region_max.x = 0.0;
  ASSERT_TRUE(Call("is_free", &inverted));
  EXPECT_FALSE(inverted.response.ok);
  EXPECT_FALSE(inverted.response.error.empty());

  // Still serving, with the map it had.
  EXPECT_TRUE(shared().node->running());
  EXPECT_EQ(NodeStatus().keyframes, kKeyframes);
  EXPECT_EQ(NodeInventory(), GrpcInventory());
}

TEST_F(RosNode, StartSessionOpensTheSessionTheStatusNamesAndRefusesABadName) {
  const objmap_msgs::Status::Response before = NodeStatus();
  ASSERT_TRUE(before.ok) << before.error;
  EXPECT_GE(before.session_id, 1);
  EXPECT_FALSE(before.session_name.empty());

  objmap_msgs::StartSession start;
  start.request.name = "after lunch";
  ASSERT_TRUE(Call("start_session", &start));
  ASSERT_TRUE(start.response.ok) << start.response.error;
  EXPECT_EQ(start.response.session_id, before.session_id + 1);
  EXPECT_EQ(start.response.session_name, "after lunch");
  const objmap_msgs::Status::Response after = NodeStatus();
  EXPECT_EQ(after.session_id, before.session_id + 1);
  EXPECT_EQ(after.session_name, "after lunch");

  objmap_msgs::StartSession bad;
  bad.request.name = "two\nlines";
  ASSERT_TRUE(Call("start_session", &bad));
  EXPECT_FALSE(bad.response.ok);
  EXPECT_NE(bad.response.error.find("control characters"), std::string::npos)
      << bad.response.error;
  // Refused: the session opened above is still the current one, and the map is whole.
  EXPECT_EQ(NodeStatus().session_id, before.session_id + 1);
  EXPECT_EQ(NodeStatus().keyframes, kKeyframes);
}

TEST_F(RosNode, BadParametersStopTheNodeAtStartWithTheReason) {
  const fs::path dir = shared().dir;
  struct Case {
    std::string parameter, expected;
  };
  const std::vector<Case> cases = {
      {"_occupancy/resolution_mm:=0.01", "~occupancy/resolution_mm: unknown parameter"},
      {"_mapper/min_detection_score:=high", "~mapper/min_detection_score: expected a number"},
      {"_keyframes/min_translation_m:=-1", "~keyframes"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::string name = "objmap_node_bad_" + std::to_string(i);
    ChildProcess node(
        {OBJMAP_NODE_PATH, "__name:=" + name, "_database:=" + (dir / (name + ".db")).string(),
         "_run_detector:=false", cases[i].parameter},
        (dir / (name + ".log")).string());
    std::string why;
    ASSERT_TRUE(node.Start(&why)) << why;
    EXPECT_EQ(node.WaitForExit(std::chrono::seconds(60)), 2) << node.Log();
    EXPECT_NE(node.Log().find(cases[i].expected), std::string::npos) << node.Log();
  }
}

// launch/objmap.launch with its defaults (objmap.example.yaml loaded as parameters) starts a
// node that passes its parameter check and serves.
TEST_F(RosNode, ObjmapLaunchStartsANodeThatServes) {
  const fs::path dir = shared().dir;
  setenv("ROS_PACKAGE_PATH", (std::string(OBJMAP_SOURCE_DIR) + ":/usr/share").c_str(), 1);
  setenv("CMAKE_PREFIX_PATH", OBJMAP_DEVEL_DIR, 1);
  ChildProcess launch({"roslaunch", std::string(OBJMAP_SOURCE_DIR) + "/launch/objmap.launch",
                       "node_name:=objmap_launched", "run_detector:=false",
                       "database:=" + (dir / "launched.db").string()},
                      (dir / "roslaunch.log").string());
  std::string why;
  ASSERT_TRUE(launch.Start(&why)) << why;
  const bool serving = ros::service::waitForService("/objmap_launched/status", ros::Duration(120));
  objmap_msgs::Status status;
  const bool answered = serving && ros::service::call("/objmap_launched/status", status);
  EXPECT_EQ(launch.Stop(SIGINT), 0) << launch.Log();
  ASSERT_TRUE(serving) << launch.Log();
  ASSERT_TRUE(answered);
  EXPECT_TRUE(status.response.ok);
  EXPECT_EQ(status.response.keyframes, 0);
  EXPECT_NE(status.response.database.find("launched.db"), std::string::npos);
}

}  // namespace
}  // namespace objmap
