// The map server under load, over real gRPC on 127.0.0.1 with a real SQLite file: latency of
// class, region and occupancy queries with the server idle and while keyframes are ingested,
// regeneration time after a pose-graph update against the number of keyframes, and bytes stored
// per keyframe. Keyframes of a recorded sequence go through the server's CenterNet detector
// (as `objmap ingest` sends them); without the model the map has no objects and the bench says so.
// Then fairness: the same keyframes sent again alone, under 1000 IsFree + RayCast queries a second
// (open loop: latency counts from when each query was due), and under 50 clients querying back
// to back. Last, restart time with the OctoMap checkpoint against re-integrating every keyframe.
//   server_bench [sequence=../shared/data/redkitchen] [keyframes=68] [query_rounds=300]
//                [fairness_keyframes=12] [busy_clients=50] [queries_per_s=1000]
//                [heavy_query_threads=config default] [heavy_query_nice=config default]
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench_timing.h"
#include "dataset/keyframe_selector.h"
#include "dataset/sequence_reader.h"
#include "detection/centernet_detector.h"
#include "grpc_service/grpc_server.h"
#include "grpc_service/map_service.h"
#include "map_server/map_server.h"
#include "objmap/client.h"
#include "objmap/conversions.h"
#include "store/keyframe_store.h"

namespace objmap {
namespace {

namespace fs = std::filesystem;
using objmap::bench::Clock;
using objmap::bench::Ms;

double Percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t index =
      std::min(values.size() - 1, static_cast<std::size_t>(p * (values.size() - 1) + 0.5));
  return values[index];
}

// The query kinds measured, each one RPC.
enum Query { kClass, kObjectRegion, kIsFree, kOccupancyCounts, kNumQueries };
const char* const kQueryNames[kNumQueries] = {
    "QueryObjects by class (cup)", "QueryObjects by region (1 m box)", "IsFree (20 cm box)",
    "QueryOccupancy counts (1 m box, 1 cm)"};

struct Latencies {
  std::mutex mutex;
  std::vector<double> ms[kNumQueries];
};

class QueryLoad {
 public:
  QueryLoad(MapClient* client, const Eigen::Vector3d& centre) : client_(client) {
    class_.set_class_name("cup");
    *region_.mutable_region() = BoxToProto(centre - Eigen::Vector3d::Constant(0.5),
                                           centre + Eigen::Vector3d::Constant(0.5));
    *is_free_.mutable_region() = BoxToProto(centre - Eigen::Vector3d::Constant(0.1),
                                            centre + Eigen::Vector3d::Constant(0.1));
    *occupancy_.mutable_region() = region_.region();
  }

  // One query of the kind; its latency in ms, negative when it failed.
  double Run(Query kind) {
    const auto start = Clock::now();
    bool ok = false;
    if (kind == kClass) {
      v1::QueryObjectsResponse response;
      ok = client_->QueryObjects(class_, &response).ok();
    } else if (kind == kObjectRegion) {
      v1::QueryObjectsResponse response;
      ok = client_->QueryObjects(region_, &response).ok();
    } else if (kind == kIsFree) {
      v1::IsFreeResponse response;
      ok = client_->IsFree(is_free_, &response).ok();
    } else {
      v1::QueryOccupancyResponse response;
      ok = client_->QueryOccupancy(occupancy_, &response).ok();
    }
    return ok ? Ms(start) : -1.0;
  }

 private:
  MapClient* client_;
  v1::QueryObjectsRequest class_, region_;
  v1::IsFreeRequest is_free_;
  v1::QueryOccupancyRequest occupancy_;
};

void PrintLatencies(const char* title, Latencies* latencies) {
  std::printf("\n%s\n| query | n | p50 ms | p99 ms | max ms |\n|---|---|---|---|---|\n", title);
  for (int q = 0; q < kNumQueries; ++q) {
    std::printf("| %s | %zu | %.2f | %.2f | %.2f |\n", kQueryNames[q], latencies->ms[q].size(),
                Percentile(latencies->ms[q], 0.5), Percentile(latencies->ms[q], 0.99),
                Percentile(latencies->ms[q], 1.0));
  }
}

// Planner-style queries at a fixed rate from `threads` threads (open loop): query i is due at
// start + i / rate whether or not the ones before it have returned, and its latency counts from
// then, so a stalled server shows as latency instead of as fewer queries sent. IsFree (20 cm
// boxes) and RayCast (1 m rays from the camera) alternate, around `centre`.
class OpenLoopQueries {
 public:
  OpenLoopQueries(MapClient* client, const Eigen::Vector3d& camera, const Eigen::Vector3d& centre,
                  double rate_per_s, int threads)
      : client_(client), camera_(camera), centre_(centre), rate_(rate_per_s) {
    start_ = Clock::now();
    for (int t = 0; t < threads; ++t) workers_.emplace_back([this, t, threads] { Run(t, threads); });
  }
  // Stops and returns the latencies: [0] IsFree, [1] RayCast.
  std::array<std::vector<double>, 2> Stop(double* achieved_rate, int* failed) {
    stopping_ = true;
    for (std::thread& worker : workers_) worker.join();
    const double seconds = Ms(start_) / 1e3;
    *achieved_rate = (ms_[0].size() + ms_[1].size() + failed_) / std::max(1e-9, seconds);
    *failed = failed_;
    return ms_;
  }

 private:
  void Run(int thread, int threads) {
    std::mt19937 random(1234 + thread);
    std::uniform_real_distribution<double> jitter(-0.5, 0.5);
    const auto period = std::chrono::duration<double>(1.0 / rate_);
    std::array<std::vector<double>, 2> local;
    int local_failed = 0;
    for (long i = thread; !stopping_; i += threads) {
      const auto due = start_ + std::chrono::duration_cast<Clock::duration>(period * i);
      std::this_thread::sleep_until(due);
      const Eigen::Vector3d target = centre_ + Eigen::Vector3d(jitter(random), jitter(random),
                                                               jitter(random));
      bool ok = false;
      if (i % 2 == 0) {
        v1::IsFreeRequest request;
        *request.mutable_region() = BoxToProto(target - Eigen::Vector3d::Constant(0.1),
                                               target + Eigen::Vector3d::Constant(0.1));
        v1::IsFreeResponse response;
        ok = client_->IsFree(request, &response).ok();
      } else {
        v1::RayCastRequest request;
        *request.mutable_origin() = Vec3ToProto(camera_);
        *request.mutable_direction() = Vec3ToProto(Eigen::Vector3d(target - camera_));
        request.set_max_range(4.0);
        v1::RayCastResponse response;
        ok = client_->RayCast(request, &response).ok();
      }
      if (ok) {
        local[i % 2].push_back(std::chrono::duration<double, std::milli>(Clock::now() - due)
                                   .count());
      } else {
        ++local_failed;
      }
    }
    std::lock_guard<std::mutex> lock(mutex_);
    for (int k = 0; k < 2; ++k) ms_[k].insert(ms_[k].end(), local[k].begin(), local[k].end());
    failed_ += local_failed;
  }

  MapClient* client_;
  Eigen::Vector3d camera_, centre_;
  double rate_;
  Clock::time_point start_;
  std::atomic<bool> stopping_{false};
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::array<std::vector<double>, 2> ms_;
  int failed_ = 0;
};

// Clients that each send the four query kinds of QueryLoad back to back, on connections of
// their own, until stopped; counts what they got answered.
class BusyClients {
 public:
  BusyClients(const std::string& address, int count, const Eigen::Vector3d& centre) {
    MapClientOptions options;
    options.deadline_s = 600.0;
    for (int c = 0; c < count; ++c) {
      clients_.push_back(std::make_unique<MapClient>(address, options));
    }
    for (int c = 0; c < count; ++c) {
      workers_.emplace_back([this, c, centre] {
        QueryLoad load(clients_[c].get(), centre);
        for (int q = c % kNumQueries; !stopping_; q = (q + 1) % kNumQueries) {
          if (load.Run(static_cast<Query>(q)) >= 0) ++answered_;
        }
      });
    }
  }
  long Stop() {
    stopping_ = true;
    for (std::thread& worker : workers_) worker.join();
    return answered_;
  }

 private:
  std::vector<std::unique_ptr<MapClient>> clients_;
  std::vector<std::thread> workers_;
  std::atomic<bool> stopping_{false};
  std::atomic<long> answered_{0};
};

}  // namespace
}  // namespace objmap

int main(int argc, char** argv) {
  using namespace objmap;
  const std::string path = argc > 1 ? argv[1] : "../shared/data/redkitchen";
  const int wanted_keyframes = argc > 2 ? std::atoi(argv[2]) : 68;
  const int query_rounds = argc > 3 ? std::atoi(argv[3]) : 300;
  const int fairness_keyframes = argc > 4 ? std::atoi(argv[4]) : 12;
  const int busy_clients = argc > 5 ? std::atoi(argv[5]) : 50;
  const double queries_per_s = argc > 6 ? std::atof(argv[6]) : 1000.0;
  std::string why;

  // Keyframes as `objmap ingest` selects and encodes them (JPEG colour).
  std::unique_ptr<SequenceReader> reader = OpenSequence(path, &why);
  if (!reader) {
    std::fprintf(stderr, "server_bench: %s\n", why.c_str());
    return 1;
  }
  KeyframeSelector selector{KeyframeSelectorConfig{}};
  KeyframeEncoding encoding;
  encoding.color = KeyframeEncoding::Color::kJpeg;
  std::vector<RgbdFrame> frames;
  for (std::size_t i = 0; i < reader->size() && static_cast<int>(frames.size()) < wanted_keyframes;
       ++i) {
    RgbdFrame frame;
    if (!reader->ReadFrame(i, &frame, &why)) {
      std::fprintf(stderr, "server_bench: %s\n", why.c_str());
      return 1;
    }
    if (selector.IsKeyframe(frame.T_W_C)) frames.push_back(std::move(frame));
  }
  const int num_keyframes = static_cast<int>(frames.size());

  // The server in this process: MapServer on a fresh SQLite file behind gRPC on loopback.
  const fs::path db =
      fs::temp_directory_path() / ("objmap_server_bench_" + std::to_string(getpid()) + ".db");
  CenterNetConfig detector_config;
  detector_config.model_path = OBJMAP_DEFAULT_MODEL_PATH;
  std::unique_ptr<Detector> detector;
  if (fs::exists(detector_config.model_path)) {
    detector = MakeCenterNetDetector(detector_config, &why);
  } else {
    std::printf("NOTE: no detector model at %s: the map will have no objects\n",
                detector_config.model_path.c_str());
  }
  MapServerConfig server_config;
  if (argc > 7) server_config.fairness.heavy_query_threads = std::atoi(argv[7]);
  if (argc > 8) server_config.fairness.heavy_query_nice = std::atoi(argv[8]);
  std::unique_ptr<MapServer> map_server =
      MapServer::Open(server_config, db.string(), std::move(detector), &why);
  if (!map_server) {
    std::fprintf(stderr, "server_bench: %s\n", why.c_str());
    return 1;
  }
  grpc_service::MapServiceImpl service(*map_server);
  grpc_service::GrpcServerOptions grpc_options;
  grpc_options.listen_address = "127.0.0.1:0";
  int port = 0;
  std::unique_ptr<grpc::Server> grpc_server =
      grpc_service::StartGrpcServer(grpc_options, &service, &port, &why);
  if (!grpc_server) {
    std::fprintf(stderr, "server_bench: %s\n", why.c_str());
    return 1;
  }
  MapClientOptions client_options;
  client_options.deadline_s = 600.0;
  MapClient client(grpc_service::AddressWithPort(grpc_options.listen_address, port),
                   client_options);
  std::printf(
      "server_bench: %s, %d keyframes, %d query rounds, heavy_query_threads %d, "
      "heavy_query_nice %d, database %s\n",
      reader->Describe().c_str(), num_keyframes, query_rounds,
      server_config.fairness.heavy_query_threads,
      server_config.fairness.heavy_query_nice, db.c_str());

  // Every later keyframe is sent with the correction of the pose updates so far, so that the
  // map stays consistent after each regeneration.
  Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translate(Eigen::Vector3d(0.05, -0.02, 0.01));
  step.rotate(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()));

  std::vector<double> ack_ms;
  int added = 0;
  auto add_until = [&](int count) {
    for (; added < count; ++added) {
      RgbdFrame frame = frames[added];
      frame.T_W_C = correction * frame.T_W_C;
      v1::AddKeyframeResponse response;
      const auto start = Clock::now();
      const grpc::Status status = client.AddKeyframe(frame, nullptr, &response);
      if (!status.ok()) {
        std::fprintf(stderr, "server_bench: keyframe %d: %s\n", added,
                     DescribeStatus(status).c_str());
        std::exit(1);
      }
      ack_ms.push_back(Ms(start));
    }
  };
  struct RegenerationPoint {
    int keyframes;
    double ms;
  };
  std::vector<RegenerationPoint> regenerations;
  auto regenerate_all = [&] {
    v1::ListKeyframesResponse listed;
    if (!client.ListKeyframes(v1::ListKeyframesRequest(), &listed).ok()) std::exit(1);
    v1::UpdatePosesRequest update;
    update.set_wait(true);
    for (const v1::KeyframeInfo& info : listed.keyframes()) {
      Eigen::Isometry3d T_W_C;
      if (!PoseFromProto(info.t_w_c(), &T_W_C, &why)) std::exit(1);
      v1::KeyframePose* pose = update.add_poses();
      pose->set_keyframe_id(info.id());
      *pose->mutable_t_w_c() = PoseToProto(step * T_W_C);
    }
    v1::UpdatePosesResponse updated;
    const grpc::Status status = client.UpdatePoses(update, &updated);
    if (!status.ok()) {
      std::fprintf(stderr, "server_bench: UpdatePoses: %s\n", DescribeStatus(status).c_str());
      std::exit(1);
    }
    correction = step * correction;
    regenerations.push_back({listed.keyframes_size(), updated.regeneration_ms()});
  };

  // Regeneration after 1/8, 1/4, 1/2 and all of the keyframes; idle queries at the half.
  const int half = num_keyframes / 2;
  for (int count : {num_keyframes / 8, num_keyframes / 4, half}) {
    add_until(count);
    regenerate_all();
  }
  const Eigen::Vector3d centre = correction * frames[0].T_W_C * Eigen::Vector3d(0, 0, 1.0);
  QueryLoad queries(&client, centre);
  Latencies idle;
  for (int round = 0; round < query_rounds; ++round) {
    for (int q = 0; q < kNumQueries; ++q) idle.ms[q].push_back(queries.Run(static_cast<Query>(q)));
  }

  // The second half of the keyframes while a client queries in a loop.
  Latencies loaded;
  std::atomic<bool> ingesting{true};
  std::atomic<int> failed{0};
  std::thread query_thread([&] {
    QueryLoad load(&client, centre);
    for (int q = 0; ingesting; q = (q + 1) % kNumQueries) {
      const double ms = load.Run(static_cast<Query>(q));
      if (ms < 0) {
        ++failed;
        continue;
      }
      std::lock_guard<std::mutex> lock(loaded.mutex);
      loaded.ms[q].push_back(ms);
    }
  });
  const std::size_t acks_before = ack_ms.size();
  add_until(num_keyframes);
  ingesting = false;
  query_thread.join();

  // Fairness: keyframes of the second half sent again (the same work each time), alone, under
  // open-loop planner queries and under busy clients.
  const std::string address = grpc_service::AddressWithPort(grpc_options.listen_address, port);
  const Eigen::Vector3d camera = (correction * frames[0].T_W_C).translation();
  auto send_again = [&]() {
    std::vector<double> ms;
    for (int k = 0; k < fairness_keyframes; ++k) {
      RgbdFrame frame = frames[half + k % std::max(1, num_keyframes - half)];
      frame.T_W_C = correction * frame.T_W_C;
      v1::AddKeyframeResponse response;
      const auto start = Clock::now();
      const grpc::Status status = client.AddKeyframe(frame, nullptr, &response);
      if (!status.ok()) {
        std::fprintf(stderr, "server_bench: fairness keyframe %d: %s\n", k,
                     DescribeStatus(status).c_str());
        std::exit(1);
      }
      ms.push_back(Ms(start));
    }
    return ms;
  };
  auto mean = [](const std::vector<double>& values) {
    double sum = 0.0;
    for (double value : values) sum += value;
    return values.empty() ? 0.0 : sum / values.size();
  };
  const std::vector<double> alone_ms = send_again();
  std::vector<double> open_loop_ms;
  std::array<std::vector<double>, 2> open_loop_latency;
  double open_loop_rate = 0.0;
  int open_loop_failed = 0;
  {
    OpenLoopQueries open_loop(&client, camera, centre, queries_per_s, 8);
    open_loop_ms = send_again();
    open_loop_latency = open_loop.Stop(&open_loop_rate, &open_loop_failed);
  }
  std::vector<double> busy_ms;
  long busy_answered = 0;
  const auto busy_start = Clock::now();
  {
    BusyClients busy(address, busy_clients, centre);
    busy_ms = send_again();
    busy_answered = busy.Stop();
  }
  const double busy_s = Ms(busy_start) / 1e3;
  regenerate_all();

  const ServerStatus status = map_server->Status();

  PrintLatencies("Queries, server idle (map of half the keyframes):", &idle);
  PrintLatencies("Queries while the second half is ingested (one query client):", &loaded);
  if (failed > 0) std::printf("FAILED queries during ingest: %d\n", failed.load());
  const std::vector<double> loaded_acks(ack_ms.begin() + acks_before, ack_ms.end());
  std::printf(
      "\nFairness: %d keyframes sent again, AddKeyframe acknowledgement\n"
      "| load | mean ms | p99 ms | vs alone |\n|---|---|---|---|\n"
      "| none | %.0f | %.0f | 1.00x |\n"
      "| %.0f IsFree + RayCast a second (achieved %.0f/s, 8 threads, open loop) | %.0f | %.0f | "
      "%.2fx |\n"
      "| %d clients querying back to back (%ld answers, %.0f/s) | %.0f | %.0f | %.2fx |\n",
      fairness_keyframes, mean(alone_ms), Percentile(alone_ms, 0.99), queries_per_s,
      open_loop_rate, mean(open_loop_ms), Percentile(open_loop_ms, 0.99),
      mean(open_loop_ms) / std::max(1e-9, mean(alone_ms)), busy_clients, busy_answered,
      busy_answered / std::max(1e-9, busy_s), mean(busy_ms), Percentile(busy_ms, 0.99),
      mean(busy_ms) / std::max(1e-9, mean(alone_ms)));
  std::printf(
      "\nOpen-loop queries during that ingest (latency from when each was due)\n"
      "| query | n | p50 ms | p99 ms | p99.9 ms | max ms |\n|---|---|---|---|---|---|\n");
  const char* const open_loop_names[2] = {"IsFree (20 cm box)", "RayCast (to 4 m)"};
  for (int k = 0; k < 2; ++k) {
    std::printf("| %s | %zu | %.2f | %.2f | %.2f | %.2f |\n", open_loop_names[k],
                open_loop_latency[k].size(), Percentile(open_loop_latency[k], 0.5),
                Percentile(open_loop_latency[k], 0.99), Percentile(open_loop_latency[k], 0.999),
                Percentile(open_loop_latency[k], 1.0));
  }
  if (open_loop_failed > 0) std::printf("FAILED open-loop queries: %d\n", open_loop_failed);
  std::printf(
      "\nAddKeyframe acknowledgement (detector, mapping, store commit): p50 %.0f ms, "
      "p99 %.0f ms over %zu keyframes\n",
      Percentile(ack_ms, 0.5), Percentile(ack_ms, 0.99), ack_ms.size());
  std::printf(
      "\nRegeneration after a pose update of every keyframe\n"
      "| keyframes | regeneration ms | ms per keyframe |\n|---|---|---|\n");
  for (const RegenerationPoint& point : regenerations) {
    std::printf("| %d | %.0f | %.0f |\n", point.keyframes, point.ms, point.ms / point.keyframes);
  }
  std::printf(
      "map: %zu keyframes, %zu objects (%zu confirmed), version %llu; OctoMap %.1f MB in memory, "
      "kept %d times\n",
      status.keyframes, status.objects, status.confirmed_objects,
      static_cast<unsigned long long>(status.map_version), status.occupancy_bytes / 1e6,
      status.occupancy_copies);

  // Restart: the map rebuilt from the file, with the OctoMap checkpoint the shutdown saved, and,
  // as the baseline, from a copy without it (every keyframe integrated again).
  grpc_server->Shutdown();
  map_server.reset();
  // Bytes per keyframe, read from the file once the server has let go of it (one writer per
  // database).
  std::unique_ptr<KeyframeStore> store =
      KeyframeStore::Open(db.string(), KeyframeStoreConfig{}, &why);
  if (!store) {
    std::fprintf(stderr, "server_bench: %s\n", why.c_str());
    return 1;
  }
  KeyframeStore::KeyframeBytes sum;
  for (KeyframeId id = 1; id <= num_keyframes; ++id) {
    const KeyframeStore::KeyframeBytes bytes = store->BytesOf(id);
    sum.depth += bytes.depth, sum.mask += bytes.mask, sum.color += bytes.color;
    sum.observations += bytes.observations, sum.total += bytes.total;
  }
  store.reset();
  const double n = std::max(1, num_keyframes);
  std::printf(
      "\nStored per keyframe (mean of %d): depth PNG %.0f kB, object mask PNG %.0f kB, "
      "colour JPEG %.0f kB, observations %.0f kB, total %.0f kB; database file %.1f MB "
      "(%.0f kB per keyframe)\n",
      num_keyframes, sum.depth / n / 1e3, sum.mask / n / 1e3, sum.color / n / 1e3,
      sum.observations / n / 1e3, sum.total / n / 1e3, status.database_bytes / 1e6,
      status.database_bytes / n / 1e3);
  std::error_code ignored;
  const auto wal_bytes = fs::file_size(db.string() + "-wal", ignored);
  std::printf("of which the WAL %.1f MB; OctoMap checkpoint of version %llu saved in %.0f ms\n",
              ignored ? 0.0 : wal_bytes / 1e6,
              static_cast<unsigned long long>(status.checkpoint_version),
              status.last_checkpoint_ms);
  const fs::path baseline_db = db.string() + ".baseline";
  fs::copy_file(db, baseline_db, fs::copy_options::overwrite_existing);
  std::uint64_t checkpoint_bytes = 0;
  {
    sqlite3* raw = nullptr;
    sqlite3_stmt* size = nullptr;
    if (sqlite3_open(db.c_str(), &raw) == SQLITE_OK &&
        sqlite3_prepare_v2(raw, "SELECT length(state) FROM occupancy_checkpoint", -1, &size,
                           nullptr) == SQLITE_OK &&
        sqlite3_step(size) == SQLITE_ROW) {
      checkpoint_bytes = static_cast<std::uint64_t>(sqlite3_column_int64(size, 0));
    }
    sqlite3_finalize(size);
    sqlite3_close(raw);
    if (sqlite3_open(baseline_db.c_str(), &raw) == SQLITE_OK) {
      sqlite3_exec(raw, "DELETE FROM occupancy_checkpoint", nullptr, nullptr, nullptr);
    }
    sqlite3_close(raw);
  }
  // The observations as the store kept them before schema 5 (points and colours), in a copy:
  // what keeping the pixels instead saves, and what rebuilding the points costs a restart.
  const fs::path points_db = db.string() + ".points";
  fs::copy_file(db, points_db, fs::copy_options::overwrite_existing);
  std::size_t observations_as_pixels = 0;
  const double in_file = static_cast<double>(std::max<std::size_t>(1, status.keyframes));
  {
    std::unique_ptr<KeyframeStore> copy =
        KeyframeStore::Open(points_db.string(), KeyframeStoreConfig{}, &why);
    StoredMap stored;
    if (!copy || !copy->LoadAll(&stored, &why)) {
      std::fprintf(stderr, "server_bench: %s\n", why.c_str());
      return 1;
    }
    StoreChange as_points;
    as_points.replace_all_objects = true;
    as_points.observations = std::move(stored.observations);
    for (StoredObservation& o : as_points.observations) {
      observations_as_pixels += o.observation.segment_pixels.empty() ? 0 : 1;
      o.observation.segment_pixels.clear();
    }
    as_points.object_summaries = std::move(stored.objects);
    if (!copy->Commit(as_points, &why)) {
      std::fprintf(stderr, "server_bench: %s\n", why.c_str());
      return 1;
    }
  }
  {
    sqlite3* raw = nullptr;
    if (sqlite3_open(points_db.c_str(), &raw) == SQLITE_OK) {
      sqlite3_exec(raw, "VACUUM", nullptr, nullptr, nullptr);
    }
    sqlite3_close(raw);
    const fs::path vacuumed = db.string() + ".vacuumed";
    fs::copy_file(db, vacuumed, fs::copy_options::overwrite_existing);
    if (sqlite3_open(vacuumed.c_str(), &raw) == SQLITE_OK) {
      sqlite3_exec(raw, "VACUUM", nullptr, nullptr, nullptr);
    }
    sqlite3_close(raw);
    std::printf(
        "\nObservations (%zu of them made from their keyframe's depth), both files vacuumed: "
        "kept as points %.1f MB, as pixels %.1f MB (%.0f / %.0f kB per keyframe of the %zu "
        "in the file)\n",
        observations_as_pixels, fs::file_size(points_db) / 1e6, fs::file_size(vacuumed) / 1e6,
        fs::file_size(points_db) / in_file / 1e3, fs::file_size(vacuumed) / in_file / 1e3,
        status.keyframes);
    fs::remove(vacuumed);
  }
  auto restart = [&](const fs::path& file, int checkpoint_every) {
    MapServerConfig config;
    config.checkpoint_every_keyframes = checkpoint_every;
    std::unique_ptr<MapServer> reopened = MapServer::Open(config, file.string(), nullptr, &why);
    if (!reopened) {
      std::fprintf(stderr, "server_bench: restart: %s\n", why.c_str());
      std::exit(1);
    }
    return reopened->Status();
  };
  const ServerStatus with_checkpoint = restart(db, 20);
  const ServerStatus without = restart(baseline_db, 0);
  const ServerStatus with_points = restart(points_db, 20);
  const ServerStatus with_pixels = restart(db, 20);
  std::printf(
      "\nRestart (open the file, decode keyframes, rebuild objects and the OctoMap), %d "
      "keyframes:\n| | startup ms | keyframes integrated |\n|---|---|---|\n"
      "| baseline: every keyframe integrated again | %.0f | %d |\n"
      "| OctoMap checkpoint (%.1f MB) | %.0f | %d |\n"
      "| **ratio** | **%.1fx** | |\n",
      num_keyframes, without.startup_ms, without.startup_keyframes_integrated,
      checkpoint_bytes / 1e6, with_checkpoint.startup_ms,
      with_checkpoint.startup_keyframes_integrated,
      without.startup_ms / std::max(1.0, with_checkpoint.startup_ms));
  std::printf(
      "\nRestart with the checkpoint, observations kept as points (before schema 5) %.0f ms, "
      "as pixels (points rebuilt from the depth) %.0f ms: %.2fx\n",
      with_points.startup_ms, with_pixels.startup_ms,
      with_points.startup_ms / std::max(1.0, with_pixels.startup_ms));
  for (const fs::path& file : {db, baseline_db, points_db}) {
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(file.string() + suffix);
  }
  return 0;
}
