// MapServiceImpl over real gRPC on 127.0.0.1 (a free port) with a real MapServer on a temporary
// SQLite file: status codes, field names in errors, the ingest stream, WatchMap, message limits.
// Keyframes are encoded by the client library, so these also check the wire format both agree on.
#include "grpc_service/map_service.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <future>
#include <random>
#include <thread>
#include <vector>

#include "grpc_service/grpc_server.h"
#include "objmap/client.h"
#include "objmap/conversions.h"
#include "objmap/keyframe_request.h"
#include "test_scenes.h"
#include "types/coco_classes.h"

namespace objmap::grpc_service {
namespace {

using testing::SceneBox;

class MapServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    db_path_ = ::testing::TempDir() + "objmap_map_service_" + std::to_string(getpid()) + "_" +
               info->name() + ".db";
    RemoveDatabase();
    K_.width = 160;  // small frames keep the test fast
    K_.height = 120;
    K_.fx = K_.fy = 146.25;
    K_.cx = 80.0;
    K_.cy = 60.0;
    Start(64);
  }
  void TearDown() override {
    Stop();
    RemoveDatabase();
  }

  void Start(int max_message_mb, GrpcServerOptions options = GrpcServerOptions(),
             std::optional<AccessTokens> tokens = std::nullopt) {
    std::string why;
    map_server_ = MapServer::Open(server_config_, db_path_, nullptr, &why);
    ASSERT_TRUE(map_server_) << why;
    service_ = std::make_unique<MapServiceImpl>(*map_server_);
    if (tokens) service_->RequireTokens(*tokens);
    options.listen_address = "127.0.0.1:0";
    options.max_receive_message_mb = max_message_mb;
    server_ = StartGrpcServer(options, service_.get(), &port_, &why);
    ASSERT_TRUE(server_) << why;
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(-1);
    arguments.SetMaxSendMessageSize(-1);
    stub_ = v1::MapService::NewStub(
        grpc::CreateCustomChannel(AddressWithPort(options.listen_address, port_),
                                  grpc::InsecureChannelCredentials(), arguments));
  }
  void Stop() {
    if (map_server_) map_server_->Shutdown();
    if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    server_.reset();
    service_.reset();
    map_server_.reset();
  }
  void RemoveDatabase() const {
    for (const char* suffix : {"", "-wal", "-shm", ".lock"}) {
      std::remove((db_path_ + suffix).c_str());
    }
  }

  // A table with a cup, seen from viewpoint `view`, with the cup's detection; with
  // `unnamed_box`, also a box beside the cup that nothing detects.
  v1::AddKeyframeRequest Keyframe(int view, bool unnamed_box = false) const {
    std::vector<SceneBox> boxes = {{{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},
                                   {{-0.05, -0.05, 0.70}, {0.05, 0.05, 0.82}, {200, 30, 30}}};
    if (unnamed_box) boxes.push_back({{0.1, 0.2, 0.70}, {0.22, 0.3, 0.80}, {40, 160, 40}});
    const Eigen::Isometry3d T_W_C =
        testing::LookAt({-1.0, 0.1 * view, 1.3}, Eigen::Vector3d(0, 0, 0.7));
    const RgbdFrame frame = testing::RenderFrame(boxes, K_, T_W_C, "view-" + std::to_string(view));
    const std::vector<Detection> detections = {
        {testing::ProjectBox(boxes[1], T_W_C, K_), CocoClassId("cup"), 0.8f}};
    v1::AddKeyframeRequest request;
    std::string why;
    EXPECT_TRUE(MakeAddKeyframeRequest(frame, &detections, KeyframeEncoding{}, &request, &why))
        << why;
    return request;
  }

  // A frame with nothing to track (one grey, a flat depth), without a pose.
  v1::AddKeyframeRequest BlankWithoutPose() const {
    RgbdFrame flat;
    flat.intrinsics = K_;
    flat.name = "blank";
    flat.color = {K_.width, K_.height, std::vector<std::uint8_t>(3u * K_.width * K_.height, 128)};
    flat.depth = {K_.width, K_.height,
                  std::vector<float>(static_cast<std::size_t>(K_.width) * K_.height, 1.5f)};
    v1::AddKeyframeRequest request;
    std::string why;
    EXPECT_TRUE(MakeAddKeyframeRequest(flat, nullptr, KeyframeEncoding{}, &request, &why)) << why;
    request.clear_t_w_c();
    return request;
  }

  // A table seen from above its edge, the scene's colours under a pattern of 6 px squares (for
  // keypoints), without a pose.
  v1::AddKeyframeRequest TexturedWithoutPose() const {
    const std::vector<SceneBox> boxes = {{{-0.6, -0.8, 0.60}, {0.6, 0.8, 0.70}, {150, 100, 60}},
                                         {{1.5, -2.0, 0.0}, {1.6, 2.0, 2.5}, {220, 220, 220}}};
    RgbdFrame textured = testing::RenderFrame(
        boxes, K_, testing::LookAt({-1.0, 0.0, 1.3}, Eigen::Vector3d(0, 0, 0.7)), "textured");
    std::mt19937 random(7);
    std::uniform_int_distribution<int> shade(40, 255);
    for (int by = 0; by < K_.height; by += 6) {
      for (int bx = 0; bx < K_.width; bx += 6) {
        const int level = shade(random);
        for (int y = by; y < std::min(by + 6, K_.height); ++y) {
          for (int x = bx; x < std::min(bx + 6, K_.width); ++x) {
            for (int c = 0; c < 3; ++c) {
              std::uint8_t& value =
                  textured.color.rgb[3u * (static_cast<std::size_t>(y) * K_.width + x) + c];
              value = static_cast<std::uint8_t>(value * level / 255);
            }
          }
        }
      }
    }
    v1::AddKeyframeRequest request;
    std::string why;
    EXPECT_TRUE(MakeAddKeyframeRequest(textured, nullptr, KeyframeEncoding{}, &request, &why))
        << why;
    request.clear_t_w_c();
    return request;
  }

  grpc::Status Add(const v1::AddKeyframeRequest& request, v1::AddKeyframeResponse* response) {
    grpc::ClientContext context;
    return stub_->AddKeyframe(&context, request, response);
  }

  std::string db_path_;
  MapServerConfig server_config_;
  int port_ = 0;
  CameraIntrinsics K_;
  std::unique_ptr<MapServer> map_server_;
  std::unique_ptr<MapServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<v1::MapService::Stub> stub_;
};

TEST_F(MapServiceTest, AServerThatEstimatesPosesTakesKeyframesWithoutOneAndSaysWhenItIsLost) {
  Stop();
  server_config_.pose_source = PoseSource::kEstimate;
  Start(64);
  // Nothing to track in a blank frame: FAILED_PRECONDITION naming why, and nothing mapped.
  const v1::AddKeyframeRequest blank = BlankWithoutPose();
  v1::AddKeyframeResponse response;
  grpc::Status status = Add(blank, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("tracking lost"), std::string::npos)
      << status.error_message();
  EXPECT_EQ(map_server_->Status().keyframes, 0u);
  // A textured view without a pose starts the map at its camera.
  const v1::AddKeyframeRequest first = TexturedWithoutPose();
  status = Add(first, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  Eigen::Isometry3d mapped_at;
  std::string why;
  ASSERT_TRUE(PoseFromProto(response.t_w_c(), &mapped_at, &why)) << why;
  EXPECT_TRUE(mapped_at.isApprox(Eigen::Isometry3d::Identity()));
  // A pose that is there is still checked, even though it would be ignored.
  v1::AddKeyframeRequest nan_pose = Keyframe(1);
  nan_pose.mutable_t_w_c()->set_qw(std::nan(""));
  status = Add(nan_pose, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

// A stream of keyframes whose poses the server estimates goes on past a keyframe it cannot
// place (a robot's stream does not stop at a blank wall): the summary counts and names it.
TEST_F(MapServiceTest, IngestWithEstimatedPosesSkipsWhatItCannotPlaceAndNamesIt) {
  Stop();
  server_config_.pose_source = PoseSource::kEstimate;
  Start(64);
  grpc::ClientContext context;
  v1::IngestSummary summary;
  auto writer = stub_->IngestKeyframes(&context, &summary);
  ASSERT_TRUE(writer->Write(BlankWithoutPose()));
  ASSERT_TRUE(writer->Write(TexturedWithoutPose()));
  ASSERT_TRUE(writer->Write(BlankWithoutPose()));
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(summary.keyframes_added(), 1);
  EXPECT_EQ(summary.first_keyframe_id(), 1);
  EXPECT_EQ(summary.last_keyframe_id(), 1);
  EXPECT_EQ(summary.keyframes_untracked(), 2);
  // Nothing to track in a blank frame: lost, not held in a provisional part.
  EXPECT_EQ(summary.keyframes_held(), 0);
  EXPECT_EQ(summary.keyframes_attached(), 0);
  ASSERT_EQ(summary.untracked_size(), 2);
  EXPECT_NE(summary.untracked(0).find("keyframe 0 (blank): blank: tracking lost"),
            std::string::npos)
      << summary.untracked(0);
  EXPECT_NE(summary.untracked(1).find("keyframe 2 (blank)"), std::string::npos)
      << summary.untracked(1);
  EXPECT_EQ(map_server_->Status().keyframes, 1u);

  // Other refusals still stop the stream, as with given poses.
  grpc::ClientContext bad_context;
  v1::IngestSummary bad_summary;
  auto bad_writer = stub_->IngestKeyframes(&bad_context, &bad_summary);
  v1::AddKeyframeRequest bad = TexturedWithoutPose();
  bad.mutable_depth()->set_width(7);
  ASSERT_TRUE(bad_writer->Write(bad));
  bad_writer->WritesDone();
  EXPECT_EQ(bad_writer->Finish().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(map_server_->Status().keyframes, 1u);
}

TEST_F(MapServiceTest, AddedKeyframeMakesAQueryableObject) {
  v1::AddKeyframeResponse added;
  const grpc::Status status = Add(Keyframe(0), &added);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(added.keyframe_id(), 1);
  EXPECT_EQ(added.detections_used(), 1);
  ASSERT_EQ(added.created_objects_size(), 1);

  grpc::ClientContext context;
  v1::QueryObjectsRequest query;
  query.set_class_name("cup");
  query.set_include_unconfirmed(true);  // one view does not pass the inventory thresholds
  v1::QueryObjectsResponse objects;
  ASSERT_TRUE(stub_->QueryObjects(&context, query, &objects).ok());
  ASSERT_EQ(objects.objects_size(), 1);
  EXPECT_EQ(objects.objects(0).class_name(), "cup");
  EXPECT_NEAR(objects.objects(0).centroid().z(), 0.76, 0.05);
  EXPECT_EQ(objects.objects(0).num_points(), 0);  // no model unless asked
  // Seen once: first and last in keyframe 1 of the server's first session.
  EXPECT_EQ(objects.objects(0).first_seen().keyframe_id(), 1);
  EXPECT_EQ(objects.objects(0).first_seen().session_id(), 1);
  EXPECT_EQ(objects.objects(0).last_seen().keyframe_id(), 1);
  EXPECT_EQ(objects.objects(0).last_seen().session_id(), 1);

  grpc::ClientContext get_context;
  v1::GetObjectRequest get;
  get.set_id(added.created_objects(0));
  get.set_include_model(true);
  v1::Object object;
  ASSERT_TRUE(stub_->GetObject(&get_context, get, &object).ok());
  EXPECT_GT(object.num_points(), 10);
  EXPECT_EQ(object.points_xyz().size(), 12u * object.num_points());
}

TEST_F(MapServiceTest, AThingNoDetectionNamesIsQueryableAsUnknownAndOutOfTheInventory) {
  v1::AddKeyframeResponse added;
  const grpc::Status status = Add(Keyframe(0, /*unnamed_box=*/true), &added);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(added.created_objects_size(), 2) << "the cup and the unnamed box";

  grpc::ClientContext context;
  v1::QueryObjectsRequest query;
  query.set_class_name("unknown");
  query.set_include_unconfirmed(true);  // one view is not yet persistence
  v1::QueryObjectsResponse objects;
  ASSERT_TRUE(stub_->QueryObjects(&context, query, &objects).ok());
  ASSERT_EQ(objects.objects_size(), 1);
  EXPECT_EQ(objects.objects(0).class_name(), "unknown");
  EXPECT_EQ(objects.objects(0).class_id(), kUnknownClassId);
  EXPECT_EQ(objects.objects(0).scores_size(), 0);
  EXPECT_NEAR(objects.objects(0).centroid().y(), 0.25, 0.04);

  grpc::ClientContext inventory_context;
  v1::InventoryRequest inventory_request;
  v1::InventoryResponse inventory;
  ASSERT_TRUE(stub_->Inventory(&inventory_context, inventory_request, &inventory).ok());
  for (const auto& entry : inventory.entries()) EXPECT_NE(entry.class_name(), "unknown");
}

// Names and nice values of this process's threads (/proc/self/task/*/comm and stat).
std::vector<std::pair<std::string, int>> ProcessThreads() {
  std::vector<std::pair<std::string, int>> threads;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::string name;
    std::getline(comm, name);
    std::ifstream stat(task.path() / "stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    // Fields after the parenthesised name: state is field 3, nice field 19.
    std::istringstream fields(text.substr(text.rfind(')') + 2));
    std::string field;
    int nice = 0;
    for (int index = 3; fields >> field; ++index) {
      if (index == 19) {
        nice = std::stoi(field);
        break;
      }
    }
    threads.emplace_back(name, nice);
  }
  return threads;
}

TEST_F(MapServiceTest, HeavyQueriesRunOnANicerThreadAndAreRefusedWhenTooManyWait) {
  Stop();
  RemoveDatabase();
  server_config_.fairness.heavy_query_threads = 1;
  server_config_.fairness.heavy_query_nice = 7;
  server_config_.fairness.max_waiting_heavy_queries = 0;
  Start(64);
  for (int view = 0; view < 2; ++view) {
    v1::AddKeyframeResponse added;
    ASSERT_TRUE(Add(Keyframe(view), &added).ok());
  }
  v1::QueryOccupancyRequest heavy;
  *heavy.mutable_region() = BoxToProto(Eigen::Vector3d(-1.2, -1.2, 0.0),
                                       Eigen::Vector3d(1.2, 1.2, 1.4));
  heavy.set_include_voxels(true);
  v1::IsFreeRequest light;
  *light.mutable_region() =
      BoxToProto(Eigen::Vector3d(-0.1, -0.1, 1.0), Eigen::Vector3d(0.1, 0.1, 1.2));
  // Bursts of simultaneous heavy and light queries: with one heavy thread and no place to wait,
  // a heavy query that finds the thread busy is refused at once; light ones never are.
  int refused = 0, heavy_answered = 0;
  for (int round = 0; round < 40 && refused == 0; ++round) {
    std::promise<void> go;
    std::shared_future<void> start = go.get_future().share();
    std::vector<std::future<grpc::Status>> heavy_calls, light_calls;
    for (int c = 0; c < 12; ++c) {
      heavy_calls.push_back(std::async(std::launch::async, [&] {
        start.wait();
        grpc::ClientContext context;
        v1::QueryOccupancyResponse response;
        return stub_->QueryOccupancy(&context, heavy, &response);
      }));
      light_calls.push_back(std::async(std::launch::async, [&] {
        start.wait();
        grpc::ClientContext context;
        v1::IsFreeResponse response;
        return stub_->IsFree(&context, light, &response);
      }));
    }
    go.set_value();
    for (auto& call : heavy_calls) {
      const grpc::Status status = call.get();
      if (status.ok()) {
        ++heavy_answered;
        continue;
      }
      ASSERT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
          << status.error_message();
      EXPECT_NE(status.error_message().find("server.max_waiting_heavy_queries"),
                std::string::npos)
          << status.error_message();
      ++refused;
    }
    for (auto& call : light_calls) {
      const grpc::Status status = call.get();
      EXPECT_TRUE(status.ok()) << status.error_message();
    }
  }
  EXPECT_GT(refused, 0) << "no heavy query found the heavy thread busy";
  EXPECT_GT(heavy_answered, 0);
  grpc::ClientContext status_context;
  v1::StatusResponse status;
  ASSERT_TRUE(stub_->Status(&status_context, v1::StatusRequest(), &status).ok());
  EXPECT_EQ(status.occupancy_copies(), 2);
  EXPECT_GT(status.occupancy_bytes(), 1000u);
  // The heavy-query thread runs 7 nicer than this one (which opened the server).
  const int own_nice = getpriority(PRIO_PROCESS, 0);
  const auto threads = ProcessThreads();
  const auto heavy_thread =
      std::find_if(threads.begin(), threads.end(),
                   [](const auto& thread) { return thread.first == "objmap-heavy"; });
  ASSERT_NE(heavy_thread, threads.end());
  EXPECT_EQ(heavy_thread->second, std::min(19, own_nice + 7));
}

TEST_F(MapServiceTest, BadRequestsGetTheirCodeAndNameTheField) {
  grpc::ClientContext get_context;
  v1::GetObjectRequest get;
  get.set_id(12345);
  v1::Object object;
  EXPECT_EQ(stub_->GetObject(&get_context, get, &object).error_code(), grpc::StatusCode::NOT_FOUND);

  grpc::ClientContext query_context;
  v1::QueryObjectsRequest query;
  query.set_class_name("unicorn");
  v1::QueryObjectsResponse objects;
  const grpc::Status unicorn = stub_->QueryObjects(&query_context, query, &objects);
  EXPECT_EQ(unicorn.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(unicorn.error_message(),
            "class_name 'unicorn' is neither a COCO class nor \"unknown\"");

  grpc::ClientContext free_context;
  v1::IsFreeRequest is_free;
  is_free.mutable_region()->mutable_min()->set_x(1.0);  // min.x > max.x
  v1::IsFreeResponse free;
  const grpc::Status box = stub_->IsFree(&free_context, is_free, &free);
  EXPECT_EQ(box.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(box.error_message().find("region.min.x"), std::string::npos) << box.error_message();

  v1::AddKeyframeRequest request = Keyframe(0);
  request.mutable_t_w_c()->set_qw(0.5);
  v1::AddKeyframeResponse added;
  const grpc::Status pose = Add(request, &added);
  EXPECT_EQ(pose.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(pose.error_message().rfind("T_W_C.q", 0), 0u) << pose.error_message();
  EXPECT_EQ(map_server_->Status().keyframes, 0u);  // nothing stored
}

TEST_F(MapServiceTest, ListKeyframesPagesThroughStoredKeyframesWithTheirCurrentPoses) {
  for (int view = 0; view < 3; ++view) {
    v1::AddKeyframeResponse added;
    v1::AddKeyframeRequest request = Keyframe(view);
    request.set_stamp(10.0 + view);
    ASSERT_TRUE(Add(request, &added).ok());
  }
  auto list = [&](std::int64_t first_id, int max_results, v1::ListKeyframesResponse* response) {
    grpc::ClientContext context;
    v1::ListKeyframesRequest request;
    request.set_first_id(first_id);
    request.set_max_results(max_results);
    return stub_->ListKeyframes(&context, request, response);
  };
  v1::ListKeyframesResponse all;
  ASSERT_TRUE(list(0, 0, &all).ok());
  EXPECT_EQ(all.map_version(), 3u);
  ASSERT_EQ(all.keyframes_size(), 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(all.keyframes(i).id(), i + 1);
    EXPECT_EQ(all.keyframes(i).name(), "view-" + std::to_string(i));
    EXPECT_DOUBLE_EQ(all.keyframes(i).stamp(), 10.0 + i);
    EXPECT_NEAR(all.keyframes(i).t_w_c().translation().y(), 0.1 * i, 1e-9);
  }
  v1::ListKeyframesResponse page;
  ASSERT_TRUE(list(2, 1, &page).ok());
  ASSERT_EQ(page.keyframes_size(), 1);
  EXPECT_EQ(page.keyframes(0).id(), 2);

  // A pose update shows in the list.
  v1::UpdatePosesRequest update;
  update.set_wait(true);
  v1::KeyframePose* moved = update.add_poses();
  moved->set_keyframe_id(3);
  *moved->mutable_t_w_c() = all.keyframes(2).t_w_c();
  moved->mutable_t_w_c()->mutable_translation()->set_x(-2.0);
  grpc::ClientContext update_context;
  v1::UpdatePosesResponse updated;
  ASSERT_TRUE(stub_->UpdatePoses(&update_context, update, &updated).ok());
  ASSERT_TRUE(list(3, 0, &page).ok());
  ASSERT_EQ(page.keyframes_size(), 1);
  EXPECT_DOUBLE_EQ(page.keyframes(0).t_w_c().translation().x(), -2.0);

  const grpc::Status negative = list(0, -1, &page);
  EXPECT_EQ(negative.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(negative.error_message(), "max_results -1 must be >= 0 (0: all)");
  const grpc::Status bad_id = list(-4, 0, &page);
  EXPECT_EQ(bad_id.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad_id.error_message(), "first_id -4 must be >= 0");
}

TEST_F(MapServiceTest, IngestStopsAtTheFirstBadKeyframeAndKeepsTheOnesBefore) {
  grpc::ClientContext context;
  v1::IngestSummary summary;
  auto writer = stub_->IngestKeyframes(&context, &summary);
  for (int view = 0; view < 3; ++view) ASSERT_TRUE(writer->Write(Keyframe(view)));
  v1::AddKeyframeRequest bad = Keyframe(3);
  bad.mutable_detections(0)->set_class_name("unicorn");
  writer->Write(bad);
  writer->Write(Keyframe(4));  // may or may not be accepted by the transport; never stored
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(),
            "keyframe 3 (view-3): detections[0].class_name 'unicorn' is not a COCO class");
  EXPECT_EQ(map_server_->Status().keyframes, 3u);

  grpc::ClientContext good_context;
  v1::IngestSummary good;
  auto good_writer = stub_->IngestKeyframes(&good_context, &good);
  for (int view = 4; view < 6; ++view) ASSERT_TRUE(good_writer->Write(Keyframe(view)));
  good_writer->WritesDone();
  ASSERT_TRUE(good_writer->Finish().ok());
  EXPECT_EQ(good.keyframes_added(), 2);
  EXPECT_EQ(good.first_keyframe_id(), 4);
  EXPECT_EQ(good.last_keyframe_id(), 5);
  EXPECT_EQ(good.map_version(), map_server_->Snapshot()->version);
}

TEST_F(MapServiceTest, WatchMapStreamsNewKeyframesUntilCancelled) {
  grpc::ClientContext context;
  v1::WatchMapRequest watch;
  auto reader = stub_->WatchMap(&context, watch);
  v1::AddKeyframeResponse added;
  ASSERT_TRUE(Add(Keyframe(0), &added).ok());
  v1::MapChange change;
  ASSERT_TRUE(reader->Read(&change));
  EXPECT_EQ(change.kind(), v1::MapChange::KEYFRAME_ADDED);
  EXPECT_EQ(change.keyframe_id(), added.keyframe_id());
  EXPECT_EQ(change.map_version(), added.map_version());
  EXPECT_EQ(change.added_objects_size(), added.created_objects_size());
  context.TryCancel();
  while (reader->Read(&change)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
}

TEST_F(MapServiceTest, WatchMapEndsUnavailableWhenTheServerShutsDown) {
  grpc::ClientContext context;
  auto reader = stub_->WatchMap(&context, v1::WatchMapRequest{});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the watch is waiting
  const auto start = std::chrono::steady_clock::now();
  map_server_->Shutdown();
  v1::MapChange change;
  while (reader->Read(&change)) {
  }
  const grpc::Status status = reader->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2 * MapServiceImpl::kWatchPoll);
}

// A stream message that does not decode (a Latin-1 name is not UTF-8) ends the stream with
// INVALID_ARGUMENT; gRPC's own decoding would end it OK and drop every later keyframe silently.
TEST_F(MapServiceTest, AStreamMessageThatDoesNotDecodeEndsTheStreamWithItsIndex) {
  grpc::ClientContext context;
  v1::IngestSummary summary;
  auto writer = stub_->IngestKeyframes(&context, &summary);
  ASSERT_TRUE(writer->Write(Keyframe(0)));
  v1::AddKeyframeRequest latin1 = Keyframe(1);
  latin1.set_name("caf\xe9-1");  // Latin-1: the byte 0xe9 alone is not UTF-8
  writer->Write(latin1);
  for (int view = 2; view < 4; ++view) writer->Write(Keyframe(view));
  writer->WritesDone();
  const grpc::Status status = writer->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("keyframe 1: cannot decode the AddKeyframeRequest", 0),
            0u)
      << status.error_message();
  EXPECT_NE(status.error_message().find("name"), std::string::npos) << status.error_message();
  EXPECT_EQ(map_server_->Status().keyframes, 1u);
}

// Bytes that are no request of the method's type get INVALID_ARGUMENT naming the type (gRPC's
// own decoding answers INTERNAL with an empty message), on every kind of method, and the server
// keeps serving.
TEST_F(MapServiceTest, UndecodableRequestsAreInvalidArgumentsNamingTheType) {
  grpc::GenericStub generic(grpc::CreateChannel(AddressWithPort("127.0.0.1:0", port_),
                                                grpc::InsecureChannelCredentials()));
  const std::string garbage = "\xff\xff\xff\xff garbage";
  const grpc::Slice slice(garbage);
  for (const char* method : {"AddKeyframe", "Inventory", "IsFree", "UpdatePoses"}) {
    grpc::ClientContext context;
    grpc::ByteBuffer request(&slice, 1);
    grpc::ByteBuffer response;
    std::promise<grpc::Status> done;
    generic.UnaryCall(&context, std::string("/objmap.v1.MapService/") + method,
                      grpc::StubOptions(), &request, &response,
                      [&done](grpc::Status status) { done.set_value(status); });
    const grpc::Status status = done.get_future().get();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << method;
    EXPECT_NE(status.error_message().find("cannot decode the "), std::string::npos)
        << method << ": " << status.error_message();
    EXPECT_LT(status.error_message().size(), 512u) << method;
  }
  // A detection's class name in Latin-1 over the typed stub: decoded by nobody, named.
  v1::AddKeyframeRequest latin1 = Keyframe(0);
  latin1.mutable_detections(0)->set_class_name("tasse \xe0 caf\xe9");
  v1::AddKeyframeResponse added;
  grpc::Status status = Add(latin1, &added);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("detections.class_name"), std::string::npos)
      << status.error_message();
  status = Add(Keyframe(0), &added);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// A 20,000-character class name is refused by the limit with a short message; before, the
// message quoted it whole and the client saw RESOURCE_EXHAUSTED from its own metadata limit.
TEST_F(MapServiceTest, LongInputIsNeverEchoedWhole) {
  v1::AddKeyframeRequest request = Keyframe(0);
  request.mutable_detections(0)->set_class_name(std::string(20000, 'x'));
  v1::AddKeyframeResponse added;
  grpc::Status status = Add(request, &added);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(status.error_message().find("server.max_string_bytes"), std::string::npos)
      << status.error_message().substr(0, 200);
  EXPECT_LT(status.error_message().size(), 512u);

  // Within the limit, an unknown class is quoted shortened; a long name in a stream too.
  request.mutable_detections(0)->set_class_name(std::string(1000, 'y'));
  status = Add(request, &added);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_LT(status.error_message().size(), 200u) << status.error_message();
  request.set_name(std::string(1000, 'n'));
  grpc::ClientContext context;
  v1::IngestSummary summary;
  auto writer = stub_->IngestKeyframes(&context, &summary);
  writer->Write(request);
  writer->WritesDone();
  status = writer->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_LT(status.error_message().size(), 300u) << status.error_message();
}

// grpc_health_probe and grpcurl work out of the box: the standard health service answers
// SERVING, and server reflection lists MapService. Spoken in raw protobuf bytes, as those tools
// would (the health and reflection messages are not part of objmap.proto).
TEST_F(MapServiceTest, HealthAndReflectionServicesAnswer) {
  const auto channel = grpc::CreateChannel(AddressWithPort("127.0.0.1:0", port_),
                                           grpc::InsecureChannelCredentials());
  grpc::GenericStub generic(channel);
  {
    grpc::ClientContext context;
    const grpc::Slice no_fields("");  // HealthCheckRequest{service: ""}: the whole server
    const grpc::ByteBuffer request(&no_fields, 1);
    grpc::ByteBuffer response;
    std::promise<grpc::Status> done;
    generic.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request,
                      &response, [&done](grpc::Status status) { done.set_value(status); });
    const grpc::Status status = done.get_future().get();
    ASSERT_TRUE(status.ok()) << status.error_message();
    std::vector<grpc::Slice> slices;
    ASSERT_TRUE(response.Dump(&slices).ok());
    std::string bytes;
    for (const grpc::Slice& slice : slices) {
      bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
    }
    EXPECT_EQ(bytes, std::string("\x08\x01", 2)) << "HealthCheckResponse{status: SERVING}";
  }
  grpc::ClientContext context;
  grpc::CompletionQueue queue;
  auto call = generic.PrepareCall(
      &context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &queue);
  void* tag = nullptr;
  bool ok = false;
  call->StartCall(reinterpret_cast<void*>(1));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  const std::string list_services("\x3a\x01*", 3);  // ServerReflectionRequest{list_services: "*"}
  const grpc::Slice request_slice(list_services);
  const grpc::ByteBuffer request(&request_slice, 1);
  call->Write(request, reinterpret_cast<void*>(2));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  grpc::ByteBuffer response;
  call->Read(&response, reinterpret_cast<void*>(3));
  ASSERT_TRUE(queue.Next(&tag, &ok) && ok);
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const grpc::Slice& slice : slices) {
    bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  }
  EXPECT_NE(bytes.find("objmap.v1.MapService"), std::string::npos);
  EXPECT_NE(bytes.find("grpc.health.v1.Health"), std::string::npos);
  call->WritesDone(reinterpret_cast<void*>(4));
  ASSERT_TRUE(queue.Next(&tag, &ok));
  context.TryCancel();
  grpc::Status finished;
  call->Finish(&finished, reinterpret_cast<void*>(5));
  while (queue.Next(&tag, &ok) && tag != reinterpret_cast<void*>(5)) {
  }
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
}

// Test-only certificates and keys (tests/data/tls/README.md).
std::string TlsFile(const std::string& name) {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind('/')) + "/../data/tls/" + name;
}

TEST(AccessTokens, ParseReadAndWriteTokensAndNameBadLines) {
  AccessTokens tokens;
  std::string why;
  ASSERT_TRUE(AccessTokens::Parse("# fleet\nread  reader-0123456789abcdef\n\nwrite "
                                  "writer-0123456789abcdef\r\n",
                                  "t.txt", &tokens, &why))
      << why;
  EXPECT_EQ(tokens.Find("reader-0123456789abcdef"), Access::kRead);
  EXPECT_EQ(tokens.Find("writer-0123456789abcdef"), Access::kReadWrite);
  EXPECT_EQ(tokens.Find("writer-0123456789abcdeF"), Access::kNone);
  EXPECT_EQ(tokens.Find(""), Access::kNone);
  EXPECT_EQ(BearerToken("Bearer abc"), "abc");
  EXPECT_EQ(BearerToken("Basic abc"), "");
  EXPECT_EQ(BearerToken("Bearer "), "");
  const std::pair<const char*, const char*> bad[] = {
      {"admin 0123456789abcdef0\n", "t.txt:1: expected 'read TOKEN' or 'write TOKEN'"},
      {"read short\n", "t.txt:1: a token is at least 16 printable characters without spaces"},
      {"read 0123456789abcdef0 extra\n", "t.txt:1: expected one token after 'read'"},
      {"read 0123456789abcdef0\nwrite 0123456789abcdef0\n", "t.txt:2: the token appears twice"},
      {"# nothing\n", "t.txt: no tokens (lines 'read TOKEN' or 'write TOKEN')"},
  };
  for (const auto& [text, reason] : bad) {
    EXPECT_FALSE(AccessTokens::Parse(text, "t.txt", &tokens, &why)) << text;
    EXPECT_EQ(why, reason);
  }
}

// TLS with client certificates and bearer tokens, through the client library: a read token
// queries but cannot write, a write token does both, no token or a wrong one is refused, and a
// plain or certificate-less client does not get through.
TEST_F(MapServiceTest, TlsClientCertificatesAndTokensGuardTheService) {
  AccessTokens tokens;
  std::string why;
  const std::string kRead = "read-token-0123456789", kWrite = "write-token-0123456789";
  ASSERT_TRUE(AccessTokens::Parse("read " + kRead + "\nwrite " + kWrite + "\n", "tokens", &tokens,
                                  &why))
      << why;
  Stop();
  GrpcServerOptions options;
  options.tls_cert_path = TlsFile("server.pem");
  options.tls_key_path = TlsFile("server.key");
  options.tls_client_ca_path = TlsFile("ca.pem");
  Start(64, options, tokens);
  const std::string address = AddressWithPort("127.0.0.1:0", port_);
  const auto client = [&](const std::string& token, bool tls, bool certificate) {
    MapClientOptions client_options;
    client_options.deadline_s = 10;
    client_options.token = token;
    if (tls) client_options.tls_ca_path = TlsFile("ca.pem");
    if (certificate) {
      client_options.tls_cert_path = TlsFile("client.pem");
      client_options.tls_key_path = TlsFile("client.key");
    }
    return std::make_unique<MapClient>(address, client_options);
  };
  v1::InventoryResponse inventory;
  v1::AddKeyframeResponse added;

  auto reader = client(kRead, true, true);
  grpc::Status status = reader->Inventory(v1::InventoryRequest(), &inventory);
  EXPECT_TRUE(status.ok()) << status.error_message();
  status = reader->AddKeyframe(Keyframe(0), &added);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(status.error_message(),
            "AddKeyframe changes the map and needs a read-write token; this one is read-only");

  auto writer = client(kWrite, true, true);
  status = writer->AddKeyframe(Keyframe(0), &added);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(map_server_->Status().keyframes, 1u);

  status = client("", true, true)->Inventory(v1::InventoryRequest(), &inventory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(status.error_message(),
            "this server needs a bearer token (metadata 'authorization: Bearer TOKEN')");
  status = client("guessed-token-0123456789", true, true)->Inventory(v1::InventoryRequest(),
                                                                     &inventory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(status.error_message(), "unknown bearer token");

  // Without TLS, or without a client certificate, no call reaches the service.
  status = client(kWrite, false, false)->Inventory(v1::InventoryRequest(), &inventory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  status = client(kWrite, true, false)->Inventory(v1::InventoryRequest(), &inventory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  EXPECT_EQ(map_server_->Status().keyframes, 1u);

  // A client whose CA file is missing says so instead of connecting.
  MapClientOptions missing_ca;
  missing_ca.tls_ca_path = TlsFile("absent.pem");
  status = MapClient(address, missing_ca).Inventory(v1::InventoryRequest(), &inventory);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("absent.pem: cannot read the CA certificate"),
            std::string::npos)
      << status.error_message();
}

TEST_F(MapServiceTest, OversizedRequestsAreRefusedAndTheServerKeepsServing) {
  Stop();
  Start(1);
  v1::AddKeyframeRequest request = Keyframe(0);
  request.mutable_color()->mutable_data()->append(2 * 1024 * 1024, '\0');
  v1::AddKeyframeResponse added;
  EXPECT_EQ(Add(request, &added).error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  const grpc::Status status = Add(Keyframe(0), &added);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(MapServiceTest, ABusyPortIsAnErrorNotASharedPort) {
  GrpcServerOptions options;
  options.listen_address = AddressWithPort("127.0.0.1:0", port_);
  MapServiceImpl second(*map_server_);
  int port = 0;
  std::string why;
  EXPECT_EQ(StartGrpcServer(options, &second, &port, &why), nullptr);
  EXPECT_NE(why.find("cannot listen on " + options.listen_address), std::string::npos) << why;
  EXPECT_EQ(AddressWithPort("[::1]:0", 4711), "[::1]:4711");
  EXPECT_EQ(AddressWithPort("localhost", 4711), "localhost:4711");
}

TEST_F(MapServiceTest, UpdatePosesRejectsRepeatedIdsAndWritesAfterShutdownAreUnavailable) {
  v1::AddKeyframeResponse added;
  ASSERT_TRUE(Add(Keyframe(0), &added).ok());
  v1::UpdatePosesRequest update;
  for (int i = 0; i < 2; ++i) {
    v1::KeyframePose* pose = update.add_poses();
    pose->set_keyframe_id(added.keyframe_id());
    pose->mutable_t_w_c()->set_qw(1.0);
  }
  grpc::ClientContext context;
  v1::UpdatePosesResponse response;
  const grpc::Status twice = stub_->UpdatePoses(&context, update, &response);
  EXPECT_EQ(twice.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(twice.error_message(), "poses[1].keyframe_id 1 appears more than once");

  map_server_->Shutdown();
  EXPECT_EQ(Add(Keyframe(1), &added).error_code(), grpc::StatusCode::UNAVAILABLE);
  grpc::ClientContext status_context;
  v1::StatusResponse status;
  ASSERT_TRUE(stub_->Status(&status_context, v1::StatusRequest{}, &status).ok());
  EXPECT_EQ(status.keyframes(), 1);  // queries keep answering
}

}  // namespace
}  // namespace objmap::grpc_service
