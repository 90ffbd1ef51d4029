// objmap end to end: the real objmap_server executable on a free loopback port with a temporary
// SQLite file and the real CenterNet detector, fed the first 52 keyframes of redkitchen through
// the client library. One server serves every case of this file (ctest runs the file as one
// test); the cases run in order and the last one moves the map.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "cli/run_objmap.h"
#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "evaluation/voxel_set.h"
#include "integration/server_process.h"
#include "objmap/client.h"
#include "objmap/conversions.h"
#include "test_data.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using testing::ServerProcess;

constexpr int kKeyframes = 52;
// The second server is killed while it works on the keyframe after this many acknowledgements:
// past its first OctoMap checkpoint (after 20 keyframes), so that the restart loads the
// checkpoint and integrates the keyframes after it.
constexpr int kAcknowledgedBeforeKill = 25;
constexpr std::chrono::seconds kStartTimeout{300};

const std::string kModelPath = std::string(OBJMAP_MODEL_DIR) + "/centernet_coco.pb";

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// class name -> object ids, as the inventory lists them (ids ascending).
using InventoryIds = std::map<std::string, std::vector<std::int64_t>>;

std::string Describe(const InventoryIds& inventory) {
  std::ostringstream text;
  for (const auto& [name, ids] : inventory) {
    text << name << " " << ids.size() << " (";
    for (std::int64_t id : ids) text << " " << id;
    text << " ) ";
  }
  return text.str();
}

grpc::Status ReadInventory(MapClient* client, InventoryIds* inventory) {
  v1::InventoryResponse response;
  const grpc::Status status = client->Inventory(v1::InventoryRequest(), &response);
  inventory->clear();
  for (const v1::InventoryEntry& entry : response.entries()) {
    std::vector<std::int64_t>& ids = (*inventory)[entry.class_name()];
    ids.assign(entry.object_ids().begin(), entry.object_ids().end());
    std::sort(ids.begin(), ids.end());
  }
  return status;
}

MapClientOptions ClientOptions() {
  MapClientOptions options;
  options.deadline_s = 300.0;  // a keyframe waits behind the queue; generous on a loaded machine
  return options;
}

// Centres of the occupied 1 cm voxels of a .bt map (pruned inner nodes expanded).
std::vector<Eigen::Vector3d> OccupiedVoxels(const std::string& bt, double* resolution) {
  octomap::OcTree tree(0.01);
  std::istringstream stream(bt);
  std::vector<Eigen::Vector3d> centres;
  if (!tree.readBinary(stream)) return centres;
  *resolution = tree.getResolution();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / *resolution));
    const octomap::point3d c = it.getCoordinate();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          centres.emplace_back(c.x() - size / 2 + (i + 0.5) * *resolution,
                               c.y() - size / 2 + (j + 0.5) * *resolution,
                               c.z() - size / 2 + (k + 0.5) * *resolution);
        }
      }
    }
  }
  return centres;
}

class ServerIntegration : public ::testing::Test {
 protected:
  // Shared by every case: the keyframes, the first server and what it answered while ingesting.
  struct Shared {
    std::string skip_reason;
    std::string setup_error;
    fs::path dir;
    std::vector<v1::AddKeyframeRequest> keyframes;
    RgbdFrame first_frame;  // keyframe 1, decoded, to find air in front of the camera
    std::unique_ptr<ServerProcess> server;
    std::unique_ptr<MapClient> client;
    // inventory_after[n]: the inventory once n keyframes were acknowledged.
    std::vector<InventoryIds> inventory_after;
    // The OctoMap (.bt) once n keyframes were acknowledged, for the n the killed server may hold.
    std::map<int, std::string> octomap_after;
    double ingest_s = 0.0;
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
    s.dir = fs::temp_directory_path() / ("objmap_integration_" + std::to_string(getpid()));
    fs::remove_all(s.dir);
    fs::create_directories(s.dir);
    std::string why;
    if (!ReadKeyframes(dataset, &why)) {
      s.setup_error = why;
      return;
    }
    s.server = StartServer("main", &why);
    if (!s.server) {
      s.setup_error = why;
      return;
    }
    s.client = std::make_unique<MapClient>(s.server->address(), ClientOptions());
    // One keyframe after the other, each acknowledged before the next is sent, so that the
    // inventory read after an acknowledgement is the map of exactly that many keyframes.
    const auto start = Clock::now();
    s.inventory_after.resize(1);
    for (int i = 0; i < kKeyframes; ++i) {
      v1::AddKeyframeResponse response;
      grpc::Status status = s.client->AddKeyframe(s.keyframes[i], &response);
      if (status.ok() && response.keyframe_id() != i + 1) {
        status = {grpc::StatusCode::INTERNAL,
                  "keyframe id " + std::to_string(response.keyframe_id())};
      }
      InventoryIds inventory;
      if (status.ok()) status = ReadInventory(s.client.get(), &inventory);
      if (!status.ok()) {
        s.setup_error = "keyframe " + std::to_string(i) + ": " + DescribeStatus(status) +
                        "\nserver log:\n" + s.server->Log();
        return;
      }
      s.inventory_after.push_back(inventory);
      if (i + 1 == kAcknowledgedBeforeKill || i + 1 == kAcknowledgedBeforeKill + 1) {
        v1::GetOctomapResponse octomap;
        status = s.client->GetOctomap(v1::GetOctomapRequest(), &octomap);
        if (!status.ok()) {
          s.setup_error = "GetOctomap: " + DescribeStatus(status);
          return;
        }
        s.octomap_after[i + 1] = octomap.bt();
      }
    }
    s.ingest_s = std::chrono::duration<double>(Clock::now() - start).count();
    std::cout << "ingested " << kKeyframes << " keyframes in " << s.ingest_s
              << " s; inventory: " << Describe(s.inventory_after.back()) << std::endl;
  }

  static void TearDownTestSuite() {
    Shared& s = shared();
    if (s.server) {
      const int exit_code = s.server->Kill(SIGTERM);
      if (exit_code != 0) std::cerr << "objmap_server exited with " << exit_code << "\n";
    }
    s.client.reset();
    s.server.reset();
    if (!s.dir.empty()) fs::remove_all(s.dir);
  }

  void SetUp() override {
    if (!shared().skip_reason.empty()) GTEST_SKIP() << shared().skip_reason;
    ASSERT_TRUE(shared().setup_error.empty()) << shared().setup_error;
  }

  // The first kKeyframes keyframes of the sequence (default keyframe selection), encoded as the
  // client sends them; the server runs its detector on them.
  static bool ReadKeyframes(const std::string& dataset, std::string* why) {
    Shared& s = shared();
    std::unique_ptr<SequenceReader> reader = OpenSequence(dataset, why);
    if (!reader) return false;
    KeyframeSelector selector{KeyframeSelectorConfig{}};
    KeyframeEncoding encoding;
    encoding.color = KeyframeEncoding::Color::kJpeg;
    for (std::size_t index = 0;
         index < reader->size() && static_cast<int>(s.keyframes.size()) < kKeyframes; ++index) {
      RgbdFrame frame;
      if (!reader->ReadFrame(index, &frame, why)) return false;
      if (!selector.IsKeyframe(frame.T_W_C)) continue;
      frame.stamp_s = static_cast<double>(index) / 30.0;
      v1::AddKeyframeRequest& request = s.keyframes.emplace_back();
      if (!MakeAddKeyframeRequest(frame, nullptr, encoding, &request, why)) return false;
      if (s.keyframes.size() == 1) s.first_frame = frame;
    }
    if (static_cast<int>(s.keyframes.size()) < kKeyframes) {
      *why = dataset + " has only " + std::to_string(s.keyframes.size()) + " keyframes";
      return false;
    }
    return true;
  }

  static std::unique_ptr<ServerProcess> StartServer(const std::string& name, std::string* why) {
    const fs::path dir = shared().dir;
    auto server = std::make_unique<ServerProcess>(
        OBJMAP_SERVER_PATH, (dir / (name + ".db")).string(), (dir / (name + ".log")).string(),
        std::vector<std::string>{"--model", kModelPath});
    if (!server->Start(kStartTimeout, why)) return nullptr;
    return server;
  }

  static MapClient& client() { return *shared().client; }

  static std::vector<v1::Object> Objects(const std::string& class_name, bool include_model,
                                         bool include_unconfirmed = false) {
    v1::QueryObjectsRequest request;
    request.set_class_name(class_name);
    request.set_include_model(include_model);
    request.set_include_unconfirmed(include_unconfirmed);
    v1::QueryObjectsResponse response;
    const grpc::Status status = client().QueryObjects(request, &response);
    EXPECT_TRUE(status.ok()) << DescribeStatus(status);
    return {response.objects().begin(), response.objects().end()};
  }

  // An 8 cm box of air in front of the first keyframe's camera: every corner projects into a
  // window of that keyframe whose depth is valid and at least 15 cm behind the corner.
  static void AirInFrontOfFirstCamera(Eigen::Vector3d* min_W, Eigen::Vector3d* max_W,
                                      std::string* problem) {
    const RgbdFrame& frame = shared().first_frame;
    const CameraIntrinsics& K = frame.intrinsics;
    auto depth_at = [&](int u, int v) {
      return frame.depth.depth_m[static_cast<std::size_t>(v) * frame.depth.width + u];
    };
    const double centre_depth = 0.6;
    const Eigen::Vector3d centre = frame.T_W_C * Eigen::Vector3d(0.0, 0.0, centre_depth);
    *min_W = centre - Eigen::Vector3d::Constant(0.04);
    *max_W = centre + Eigen::Vector3d::Constant(0.04);
    double u_min = K.width, u_max = 0, v_min = K.height, v_max = 0, z_max = 0;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p_W((corner & 1) ? max_W->x() : min_W->x(),
                                (corner & 2) ? max_W->y() : min_W->y(),
                                (corner & 4) ? max_W->z() : min_W->z());
      const Eigen::Vector3d p_C = frame.T_W_C.inverse() * p_W;
      const double u = K.fx * p_C.x() / p_C.z() + K.cx, v = K.fy * p_C.y() / p_C.z() + K.cy;
      u_min = std::min(u_min, u), u_max = std::max(u_max, u);
      v_min = std::min(v_min, v), v_max = std::max(v_max, v);
      z_max = std::max(z_max, p_C.z());
    }
    if (u_min < 0 || v_min < 0 || u_max >= K.width || v_max >= K.height) {
      *problem = "the box leaves the first keyframe's image";
      return;
    }
    int valid = 0, total = 0;
    float nearest = std::numeric_limits<float>::infinity();
    for (int v = static_cast<int>(v_min); v <= static_cast<int>(v_max); ++v) {
      for (int u = static_cast<int>(u_min); u <= static_cast<int>(u_max); ++u) {
        ++total;
        const float d = depth_at(u, v);
        if (std::isfinite(d) && d > 0.f) {
          ++valid;
          nearest = std::min(nearest, d);
        }
      }
    }
    if (valid < 0.95 * total || nearest < z_max + 0.15) {
      std::ostringstream text;
      text << "the first keyframe does not see past the box: " << valid << " of " << total
           << " pixels with depth, nearest " << nearest << " m, box reaches " << z_max << " m";
      *problem = text.str();
    }
  }
};

TEST_F(ServerIntegration, ObjectsByClassRegionAndNearest) {
  const std::vector<v1::Object> cups = Objects("cup", false);
  const std::vector<v1::Object> tables = Objects("dining table", false);
  ASSERT_GE(cups.size(), 1u);
  ASSERT_EQ(tables.size(), 1u);
  for (const v1::Object& cup : cups) {
    EXPECT_EQ(cup.class_name(), "cup");
    EXPECT_TRUE(cup.confirmed());
    EXPECT_GE(cup.observations(), 3);
  }
  // The mugs stand on the table: a box around the table holds the table and every cup.
  const v1::Object& table = tables[0];
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.15);
  const Eigen::Vector3d table_min = Vec3FromProto(table.bounds().min()) - margin;
  const Eigen::Vector3d table_max = Vec3FromProto(table.bounds().max()) + margin;
  v1::QueryObjectsRequest region;
  *region.mutable_region() = BoxToProto(table_min, table_max);
  v1::QueryObjectsResponse in_region;
  ASSERT_TRUE(client().QueryObjects(region, &in_region).ok());
  std::set<std::int64_t> region_ids;
  for (const v1::Object& object : in_region.objects()) {
    region_ids.insert(object.id());
    const Eigen::Vector3d c = Vec3FromProto(object.centroid());
    EXPECT_TRUE((c.array() >= table_min.array()).all() && (c.array() <= table_max.array()).all())
        << object.class_name() << " " << object.id() << " outside the region";
  }
  EXPECT_EQ(region_ids.count(table.id()), 1u);
  for (const v1::Object& cup : cups) EXPECT_EQ(region_ids.count(cup.id()), 1u) << cup.id();
  // A box of the same size 20 m away holds nothing.
  *region.mutable_region() =
      BoxToProto(table_min + Eigen::Vector3d(20, 0, 0), table_max + Eigen::Vector3d(20, 0, 0));
  ASSERT_TRUE(client().QueryObjects(region, &in_region).ok());
  EXPECT_EQ(in_region.objects_size(), 0);

  // Nearest to a cup's centroid: that cup; with its 5 mm model on request.
  v1::QueryObjectsRequest nearest;
  *nearest.mutable_nearest_to() = cups.back().centroid();
  nearest.set_max_results(1);
  nearest.set_include_model(true);
  v1::QueryObjectsResponse found;
  ASSERT_TRUE(client().QueryObjects(nearest, &found).ok());
  ASSERT_EQ(found.objects_size(), 1);
  EXPECT_EQ(found.objects(0).id(), cups.back().id());
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<std::uint8_t, 3>> colors;
  std::string why;
  ASSERT_TRUE(DecodeObjectModel(found.objects(0), &points, &colors, &why)) << why;
  EXPECT_GT(points.size(), 50u);

  v1::GetObjectRequest get;
  get.set_id(987654);
  v1::Object missing;
  EXPECT_EQ(client().GetObject(get, &missing).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(ServerIntegration, InventoryCountsTheConfirmedObjectsOfEachClass) {
  v1::InventoryResponse inventory;
  ASSERT_TRUE(client().Inventory(v1::InventoryRequest(), &inventory).ok());
  ASSERT_GT(inventory.entries_size(), 0);
  int total = 0;
  for (const v1::InventoryEntry& entry : inventory.entries()) {
    const std::vector<v1::Object> objects = Objects(entry.class_name(), false);
    EXPECT_EQ(entry.count(), static_cast<int>(objects.size())) << entry.class_name();
    EXPECT_EQ(entry.object_ids_size(), entry.count());
    EXPECT_GT(entry.mean_confidence(), 0.f);
    total += entry.count();
  }
  v1::StatusResponse status;
  ASSERT_TRUE(client().Status(v1::StatusRequest(), &status).ok());
  EXPECT_EQ(status.keyframes(), kKeyframes);
  EXPECT_EQ(status.confirmed_objects(), total);
  EXPECT_EQ(status.map_version(), static_cast<std::uint64_t>(kKeyframes));
  std::cout << "inventory: " << Describe(shared().inventory_after.back()) << "; "
            << status.objects() << " objects in all" << std::endl;
}

TEST_F(ServerIntegration, AirInFrontOfTheCameraIsFreeAndTheTableTopIsNot) {
  Eigen::Vector3d air_min, air_max;
  std::string problem;
  AirInFrontOfFirstCamera(&air_min, &air_max, &problem);
  ASSERT_TRUE(problem.empty()) << problem;
  v1::IsFreeRequest request;
  *request.mutable_region() = BoxToProto(air_min, air_max);
  v1::IsFreeResponse air;
  ASSERT_TRUE(client().IsFree(request, &air).ok());
  EXPECT_TRUE(air.free()) << air.occupied() << " occupied, " << air.unknown() << " unknown, "
                          << air.object_ids_size() << " objects";

  // A box around a point of the table top: not free, even for a planner that takes unknown
  // space as free, because the table (an object, not OctoMap voxels) is in it.
  const std::vector<v1::Object> tables = Objects("dining table", true);
  ASSERT_EQ(tables.size(), 1u);
  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<std::uint8_t, 3>> colors;
  std::string why;
  ASSERT_TRUE(DecodeObjectModel(tables[0], &points, &colors, &why)) << why;
  const Eigen::Vector3f centroid = Vec3FromProto(tables[0].centroid()).cast<float>();
  const Eigen::Vector3f on_top = *std::min_element(
      points.begin(), points.end(), [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
        return (a - centroid).squaredNorm() < (b - centroid).squaredNorm();
      });
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.03);
  *request.mutable_region() =
      BoxToProto(on_top.cast<double>() - half, on_top.cast<double>() + half);
  for (bool unknown_is_free : {false, true}) {
    request.set_unknown_is_free(unknown_is_free);
    v1::IsFreeResponse table_top;
    ASSERT_TRUE(client().IsFree(request, &table_top).ok());
    EXPECT_FALSE(table_top.free());
    EXPECT_TRUE(std::count(table_top.object_ids().begin(), table_top.object_ids().end(),
                           tables[0].id()) == 1)
        << "the table is not named among the objects in the box";
  }

  // A ray towards that point of the table top from 30 cm away, on the side of a camera that saw
  // the table, stops at the table.
  ASSERT_GT(tables[0].keyframes_size(), 0);
  v1::ListKeyframesRequest which;
  which.set_first_id(tables[0].keyframes(0));
  which.set_max_results(1);
  v1::ListKeyframesResponse seen_from;
  ASSERT_TRUE(client().ListKeyframes(which, &seen_from).ok());
  ASSERT_EQ(seen_from.keyframes_size(), 1);
  const Eigen::Vector3d camera = Vec3FromProto(seen_from.keyframes(0).t_w_c().translation());
  const Eigen::Vector3d target = on_top.cast<double>();
  const Eigen::Vector3d origin = target + 0.3 * (camera - target).normalized();
  v1::RayCastRequest ray;
  *ray.mutable_origin() = Vec3ToProto(origin);
  *ray.mutable_direction() = Vec3ToProto(Eigen::Vector3d(target - origin));
  ray.set_max_range(1.0);
  v1::RayCastResponse ray_hit;
  ASSERT_TRUE(client().RayCast(ray, &ray_hit).ok());
  EXPECT_TRUE(ray_hit.hit());
  EXPECT_EQ(ray_hit.object_id(), tables[0].id());
  EXPECT_NEAR(ray_hit.distance(), 0.3, 0.02);

  // The same box of air by QueryOccupancy: known free voxels, none occupied.
  v1::QueryOccupancyRequest occupancy;
  *occupancy.mutable_region() = BoxToProto(air_min, air_max);
  v1::QueryOccupancyResponse counts;
  ASSERT_TRUE(client().QueryOccupancy(occupancy, &counts).ok());
  EXPECT_EQ(counts.occupied(), 0u);
  EXPECT_GT(counts.free(), 0u);
}

TEST_F(ServerIntegration, KilledDuringIngestKeepsEveryAcknowledgedKeyframeAndTheInventory) {
  Shared& s = shared();
  std::string why;
  std::unique_ptr<ServerProcess> server = StartServer("killed", &why);
  ASSERT_TRUE(server) << why;
  MapClient killed_client(server->address(), ClientOptions());

  // A writer adds keyframes one by one; once kAcknowledgedBeforeKill are acknowledged the server
  // is killed while it works on the next one.
  std::mutex mutex;
  std::vector<std::int64_t> acknowledged;  // keyframe ids, in order
  InventoryIds inventory_at_last_ack;
  std::atomic<bool> writer_done{false};
  std::thread writer([&] {
    for (int i = 0; i < kKeyframes; ++i) {
      v1::AddKeyframeResponse response;
      if (!killed_client.AddKeyframe(s.keyframes[i], &response).ok()) break;
      InventoryIds inventory;
      const bool read = ReadInventory(&killed_client, &inventory).ok();
      std::lock_guard<std::mutex> lock(mutex);
      acknowledged.push_back(response.keyframe_id());
      if (!read) break;
      inventory_at_last_ack = inventory;
    }
    writer_done = true;
  });
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (static_cast<int>(acknowledged.size()) >= kAcknowledgedBeforeKill) break;
    }
    if (writer_done) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // The next keyframe is on its way (a keyframe takes several hundred milliseconds).
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  EXPECT_EQ(server->Kill(SIGKILL), 128 + SIGKILL);
  writer.join();
  const std::size_t acked = acknowledged.size();
  ASSERT_GE(static_cast<int>(acked), kAcknowledgedBeforeKill) << server->Log();
  ASSERT_LT(static_cast<int>(acked), kKeyframes);

  ASSERT_TRUE(server->Start(kStartTimeout, &why)) << why;
  MapClient restarted(server->address(), ClientOptions());
  v1::ListKeyframesResponse listed;
  ASSERT_TRUE(restarted.ListKeyframes(v1::ListKeyframesRequest(), &listed).ok());
  const std::size_t stored = static_cast<std::size_t>(listed.keyframes_size());
  // Every acknowledged keyframe is there, as sent; the one in flight may have been stored too.
  ASSERT_TRUE(stored == acked || stored == acked + 1) << stored << " stored, " << acked << " acked";
  for (std::size_t i = 0; i < stored; ++i) {
    const v1::KeyframeInfo& info = listed.keyframes(static_cast<int>(i));
    if (i < acked) {
      EXPECT_EQ(info.id(), acknowledged[i]);
    }
    EXPECT_EQ(info.name(), s.keyframes[i].name());
    EXPECT_DOUBLE_EQ(info.stamp(), s.keyframes[i].stamp());
    const Eigen::Vector3d sent = Vec3FromProto(s.keyframes[i].t_w_c().translation());
    EXPECT_LT((Vec3FromProto(info.t_w_c().translation()) - sent).norm(), 1e-9);
  }
  v1::StatusResponse status;
  ASSERT_TRUE(restarted.Status(v1::StatusRequest(), &status).ok());
  EXPECT_EQ(status.keyframes(), static_cast<std::int64_t>(stored));

  // The same inventory: as the killed server answered after its last acknowledgement (when the
  // keyframe in flight was lost), and as the uninterrupted server had after as many keyframes.
  InventoryIds inventory;
  ASSERT_TRUE(ReadInventory(&restarted, &inventory).ok());
  if (stored == acked) {
    EXPECT_EQ(inventory, inventory_at_last_ack)
        << "restarted: " << Describe(inventory) << "\nbefore: " << Describe(inventory_at_last_ack);
  }
  EXPECT_EQ(inventory, s.inventory_after[stored])
      << "restarted: " << Describe(inventory)
      << "\nuninterrupted: " << Describe(s.inventory_after[stored]);
  // The same OctoMap, byte for byte, as the uninterrupted server had after as many keyframes,
  // whether the restart loaded a checkpoint or integrated the keyframes again.
  v1::GetOctomapResponse octomap;
  ASSERT_TRUE(restarted.GetOctomap(v1::GetOctomapRequest(), &octomap).ok());
  ASSERT_EQ(s.octomap_after.count(static_cast<int>(stored)), 1u);
  EXPECT_TRUE(octomap.bt() == s.octomap_after[static_cast<int>(stored)])
      << "the restarted OctoMap differs from the uninterrupted one";
  std::cout << "killed after " << acked << " acknowledged keyframes; " << stored
            << " stored; inventory " << Describe(inventory) << "; restart took "
            << status.startup_ms() << " ms, " << status.startup_keyframes_integrated()
            << " keyframes integrated (checkpoint of version " << status.checkpoint_version() << ")"
            << std::endl;
  EXPECT_EQ(server->Kill(SIGTERM), 0) << server->Log();
}

// The objmap command against the same server answers what the API answers.
TEST_F(ServerIntegration, CliInventoryFreeAndExportAgreeWithTheApi) {
  const std::string server = " --server " + shared().server->address();
  const testing::CommandResult inventory = testing::RunObjmap("inventory" + server);
  ASSERT_EQ(inventory.exit_code, 0) << inventory.output;
  for (const auto& [name, ids] : shared().inventory_after.back()) {
    // "cup                  2       0.471": the class and its count on one line.
    const std::size_t line = inventory.output.find("\n" + name + " ");
    ASSERT_NE(line, std::string::npos) << name << " missing in:\n" << inventory.output;
    std::istringstream fields(inventory.output.substr(line + 1 + name.size()));
    int count = -1;
    fields >> count;
    EXPECT_EQ(count, static_cast<int>(ids.size())) << name;
  }

  Eigen::Vector3d air_min, air_max;
  std::string problem;
  AirInFrontOfFirstCamera(&air_min, &air_max, &problem);
  ASSERT_TRUE(problem.empty()) << problem;
  std::ostringstream air;
  air << "free " << air_min.x() << " " << air_min.y() << " " << air_min.z() << " " << air_max.x()
      << " " << air_max.y() << " " << air_max.z();
  const testing::CommandResult free = testing::RunObjmap(air.str() + server);
  EXPECT_EQ(free.exit_code, 0) << free.output;
  const std::vector<v1::Object> tables = Objects("dining table", false);
  ASSERT_EQ(tables.size(), 1u);
  const Eigen::Vector3d c = Vec3FromProto(tables[0].centroid());
  std::ostringstream table_box;
  table_box << "free " << c.x() - 0.1 << " " << c.y() - 0.1 << " " << c.z() - 0.1 << " "
            << c.x() + 0.1 << " " << c.y() + 0.1 << " " << c.z() + 0.1 << " --unknown-is-free";
  const testing::CommandResult blocked = testing::RunObjmap(table_box.str() + server);
  EXPECT_EQ(blocked.exit_code, 3) << blocked.output;
  EXPECT_NE(blocked.output.find(std::to_string(tables[0].id())), std::string::npos)
      << blocked.output;

  // export: the .bt is the server's OctoMap, and one PLY per confirmed object.
  const fs::path out = shared().dir / "export";
  const testing::CommandResult exported =
      testing::RunObjmap("export --octomap " + (out / "map.bt").string() + " --objects " +
                         (out / "objects").string() + server);
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  v1::GetOctomapResponse octomap;
  ASSERT_TRUE(client().GetOctomap(v1::GetOctomapRequest(), &octomap).ok());
  std::ifstream file(out / "map.bt", std::ios::binary);
  const std::string written((std::istreambuf_iterator<char>(file)),
                            std::istreambuf_iterator<char>());
  EXPECT_TRUE(written == octomap.bt()) << "map.bt differs from GetOctomap";
  std::size_t plys = 0;
  for (const auto& entry : fs::directory_iterator(out / "objects")) {
    plys += entry.path().extension() == ".ply";
  }
  // Confirmed objects: those the inventory counts and the unknown ones, which it does not.
  std::size_t confirmed = 0;
  for (const auto& [name, ids] : shared().inventory_after.back()) confirmed += ids.size();
  v1::QueryObjectsRequest unknown_request;
  unknown_request.set_class_name("unknown");
  v1::QueryObjectsResponse unknown;
  ASSERT_TRUE(client().QueryObjects(unknown_request, &unknown).ok());
  EXPECT_EQ(plys, confirmed + static_cast<std::size_t>(unknown.objects_size()));
  EXPECT_TRUE(fs::exists(out / "objects" / "objects.json"));

  // eval, on the server and on the exported folder: the same objects, the same scores.
  const std::string counts =
      std::string(OBJMAP_SOURCE_DIR) + "/tests/eval/redkitchen_inventory.json";
  const testing::CommandResult on_server = testing::RunObjmap("eval " + shared().server->address() +
                                                              " --inventory " + counts + " --json");
  ASSERT_EQ(on_server.exit_code, 0) << on_server.output;
  const testing::CommandResult on_folder = testing::RunObjmap("eval " + (out / "objects").string() +
                                                              " --inventory " + counts + " --json");
  ASSERT_EQ(on_folder.exit_code, 0) << on_folder.output;
  EXPECT_EQ(on_server.output, on_folder.output);
  EXPECT_NE(on_server.output.find("\"mapped\": " + std::to_string(confirmed)), std::string::npos)
      << on_server.output;
}

// objmap render --server: a picture of the server's map whose legend is the server's inventory.
TEST_F(ServerIntegration, CliRenderDrawsTheServersInventory) {
  const fs::path picture = shared().dir / "render" / "top.png";
  fs::create_directories(picture.parent_path());
  const testing::CommandResult render = testing::RunObjmap(
      "render --server " + shared().server->address() + " --out " + picture.string() +
      " --view top");
  ASSERT_EQ(render.exit_code, 0) << render.output;
  // "legend: chair 3; cup 2; ...": every inventory class with its count (unknown objects, which
  // the inventory does not count, may come on top).
  const std::size_t legend = render.output.find("legend:");
  ASSERT_NE(legend, std::string::npos) << render.output;
  const std::string line = render.output.substr(legend, render.output.find('\n', legend) - legend);
  for (const auto& [name, ids] : shared().inventory_after.back()) {
    EXPECT_NE(line.find(" " + name + " " + std::to_string(ids.size()) + ";"), std::string::npos)
        << name << " " << ids.size() << " missing in: " << line;
  }
  std::ifstream file(picture, std::ios::binary);
  const std::string png((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  // The folder the map went through (objmap_render_<pid>) is gone.
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path())) {
    const std::string name = entry.path().filename().string();
    const bool render_folder =
        entry.is_directory() && name.rfind("objmap_render_", 0) == 0 &&
        name.find_first_not_of("0123456789", 14) == std::string::npos;
    EXPECT_FALSE(render_folder) << entry.path();
  }
}

TEST_F(ServerIntegration, CliExportsKeyframePosesThatUpdatePosesTakesBackUnmoved) {
  const std::string poses = (shared().dir / "poses.txt").string();
  const std::string server = " --server " + shared().server->address();
  std::map<std::int64_t, std::uint64_t> changed_before;
  for (const v1::Object& object : Objects("", false, true)) {
    changed_before[object.id()] = object.changed_version();
  }
  const testing::CommandResult exported = testing::RunObjmap("keyframes --out " + poses + server);
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  EXPECT_NE(exported.output.find(std::to_string(kKeyframes) + " keyframes written"),
            std::string::npos)
      << exported.output;
  // The file is what update-poses reads; the same poses sent back move nothing.
  const testing::CommandResult update =
      testing::RunObjmap("update-poses " + poses + " --wait" + server);
  ASSERT_EQ(update.exit_code, 0) << update.output;
  EXPECT_NE(update.output.find(": 0 of " + std::to_string(kKeyframes) + " keyframes moved"),
            std::string::npos)
      << update.output;
  // Nothing was rebuilt: every object is as it was.
  std::map<std::int64_t, std::uint64_t> changed_after;
  for (const v1::Object& object : Objects("", false, true)) {
    changed_after[object.id()] = object.changed_version();
  }
  EXPECT_EQ(changed_after, changed_before);
}

// Last: moves the shared map.
TEST_F(ServerIntegration, RigidPoseUpdateMovesObjectsAndOccupancyWhileQueriesAnswer) {
  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  G.translate(Eigen::Vector3d(0.4, -0.3, 0.2));
  G.rotate(Eigen::AngleAxisd(0.35, Eigen::Vector3d(0.2, 1.0, 0.3).normalized()));

  const std::vector<v1::Object> before = Objects("", false, /*include_unconfirmed=*/true);
  ASSERT_FALSE(before.empty());
  v1::GetOctomapResponse octomap_before;
  ASSERT_TRUE(client().GetOctomap(v1::GetOctomapRequest(), &octomap_before).ok());
  double resolution = 0.0;
  const std::vector<Eigen::Vector3d> occupied_before =
      OccupiedVoxels(octomap_before.bt(), &resolution);
  ASSERT_GT(occupied_before.size(), 10000u);
  ASSERT_DOUBLE_EQ(resolution, 0.01);

  v1::ListKeyframesResponse keyframes;
  ASSERT_TRUE(client().ListKeyframes(v1::ListKeyframesRequest(), &keyframes).ok());
  ASSERT_EQ(keyframes.keyframes_size(), kKeyframes);
  v1::UpdatePosesRequest update;
  for (const v1::KeyframeInfo& info : keyframes.keyframes()) {
    Eigen::Isometry3d T_W_C;
    std::string why;
    ASSERT_TRUE(PoseFromProto(info.t_w_c(), &T_W_C, &why)) << why;
    v1::KeyframePose* pose = update.add_poses();
    pose->set_keyframe_id(info.id());
    *pose->mutable_t_w_c() = PoseToProto(G * T_W_C);
  }

  // Queries run on their own thread from before the update until the new version is served.
  std::atomic<bool> stop{false};
  std::atomic<int> failures{0}, answered_while_regenerating{0};
  std::vector<double> latencies_ms;
  std::thread reader([&] {
    v1::QueryObjectsRequest cups;
    cups.set_class_name("cup");
    v1::IsFreeRequest is_free;
    *is_free.mutable_region() =
        BoxToProto(Eigen::Vector3d::Constant(-0.05), Eigen::Vector3d::Constant(0.05));
    while (!stop) {
      v1::StatusResponse status;
      const bool regenerating =
          client().Status(v1::StatusRequest(), &status).ok() && status.regenerating();
      const auto start = Clock::now();
      v1::QueryObjectsResponse objects;
      v1::IsFreeResponse free;
      v1::InventoryResponse inventory;
      const bool ok = client().QueryObjects(cups, &objects).ok() &&
                      client().IsFree(is_free, &free).ok() &&
                      client().Inventory(v1::InventoryRequest(), &inventory).ok();
      latencies_ms.push_back(Ms(Clock::now() - start));
      if (!ok) ++failures;
      if (ok && regenerating) ++answered_while_regenerating;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  v1::UpdatePosesResponse updated;
  const grpc::Status update_status = client().UpdatePoses(update, &updated);
  const auto deadline = Clock::now() + std::chrono::minutes(15);
  v1::StatusResponse status;
  while (update_status.ok() && Clock::now() < deadline) {
    if (client().Status(v1::StatusRequest(), &status).ok() &&
        status.last_regeneration_version() >= updated.map_version() && !status.regenerating()) {
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  stop = true;
  reader.join();
  ASSERT_TRUE(update_status.ok()) << DescribeStatus(update_status);
  ASSERT_GE(status.last_regeneration_version(), updated.map_version()) << "regeneration not done";
  EXPECT_EQ(status.map_version(), updated.map_version());

  EXPECT_EQ(failures.load(), 0);
  EXPECT_GT(answered_while_regenerating.load(), 0);
  std::sort(latencies_ms.begin(), latencies_ms.end());
  ASSERT_FALSE(latencies_ms.empty());
  const double slowest_ms = latencies_ms.back();
  // No query waited for the regeneration.
  EXPECT_LT(slowest_ms, 0.25 * status.last_regeneration_ms());
  std::cout << "regeneration of " << kKeyframes << " keyframes: " << status.last_regeneration_ms()
            << " ms; " << latencies_ms.size() << " query rounds meanwhile ("
            << answered_while_regenerating << " while regenerating), median "
            << latencies_ms[latencies_ms.size() / 2] << " ms, slowest " << slowest_ms << " ms"
            << std::endl;

  // Every object kept its id and moved with the poses.
  const std::vector<v1::Object> after = Objects("", false, true);
  std::map<std::int64_t, Eigen::Vector3d> centroid_after;
  for (const v1::Object& object : after)
    centroid_after[object.id()] = Vec3FromProto(object.centroid());
  EXPECT_EQ(after.size(), before.size());
  double worst_centroid_m = 0.0;
  for (const v1::Object& object : before) {
    const auto it = centroid_after.find(object.id());
    ASSERT_NE(it, centroid_after.end()) << "object " << object.id() << " lost";
    const double moved_by = (it->second - G * Vec3FromProto(object.centroid())).norm();
    worst_centroid_m = std::max(worst_centroid_m, moved_by);
    EXPECT_LT(moved_by, 0.01) << object.class_name() << " " << object.id();
  }

  // Every occupied voxel moved with the poses: the moved centre of each old occupied voxel has
  // an occupied voxel centre of the new map within 1 cm. A rotated grid re-quantizes each
  // measured point by up to half a voxel diagonal twice, so a small share lies a little further.
  v1::GetOctomapResponse octomap_after;
  ASSERT_TRUE(client().GetOctomap(v1::GetOctomapRequest(), &octomap_after).ok());
  const std::vector<Eigen::Vector3d> occupied_after =
      OccupiedVoxels(octomap_after.bt(), &resolution);
  VoxelSet after_set(resolution);
  for (const Eigen::Vector3d& c : occupied_after) after_set.Insert(c);
  std::size_t within_1cm = 0, within_2cm = 0;
  for (const Eigen::Vector3d& c : occupied_before) {
    const double d = after_set.NearestCenterDistance(G * c);
    within_1cm += d <= 0.01;
    within_2cm += d <= 0.02;
  }
  const double share_1cm = static_cast<double>(within_1cm) / occupied_before.size();
  const double share_2cm = static_cast<double>(within_2cm) / occupied_before.size();
  std::cout << "occupied voxels " << occupied_before.size() << " -> " << occupied_after.size()
            << "; moved centre within 1 cm of an occupied voxel: " << 100.0 * share_1cm
            << " %, within 2 cm: " << 100.0 * share_2cm << " %; worst object centroid "
            << 1000.0 * worst_centroid_m << " mm" << std::endl;
  EXPECT_GT(share_1cm, 0.97);
  EXPECT_GT(share_2cm, 0.995);
  EXPECT_NEAR(static_cast<double>(occupied_after.size()) / occupied_before.size(), 1.0, 0.05);
}

}  // namespace
}  // namespace objmap
