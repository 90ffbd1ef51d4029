// objmap_server: MapServer behind gRPC. Prints one "objmap_server listening on ..." line to
// stdout once it serves (scripts and tests wait for it), everything else to stderr.
#include <csignal>
#include <cstdio>
#include <iostream>

#include "config/build_info.h"
#include "config/objmap_config.h"
#include "detection/centernet_detector.h"
#include "detection/model_location.h"
#include "grpc_service/grpc_server.h"
#include "grpc_service/map_service.h"
#include "http_viewer/http_viewer.h"
#include "map_server/map_server.h"
#include "server_options.h"

namespace objmap {
namespace {

// Connections get this long to finish their calls after SIGINT/SIGTERM; then they are cancelled.
constexpr std::chrono::seconds kShutdownGrace{5};

// The configuration: the defaults, then the file, then --set keys, then the other flags.
bool LoadConfig(const ServerOptions& options, ObjmapConfig* config, std::string* why) {
  if (!ReadObjmapConfig(options.config_path, options.config_keys, config, why)) return false;
  if (!options.model_path.empty()) config->detector.model_path = options.model_path;
  return config->IsValid(why);
}

// The detector, or nullptr (no detector) when disabled or its model is missing; false only when
// a model exists but cannot be loaded (a broken installation should not go unnoticed).
bool MakeDetector(const ServerOptions& options, const CenterNetConfig& config,
                  std::unique_ptr<Detector>* detector, std::string* why) {
  if (options.no_detector) return true;
  CenterNetConfig found = config;
  std::string missing;
  if (!FindDetectorModel(config.model_path, &found.model_path, &missing)) {
    std::cerr << "objmap_server: warning: " << missing
              << "\nrunning without a detector, so keyframes sent without detections add no "
                 "objects (--no-detector silences this)\n";
    return true;
  }
  *detector = MakeCenterNetDetector(found, why);
  if (*detector) std::cerr << "objmap_server: detector " << found.model_path << "\n";
  return *detector != nullptr;
}

// SIGINT and SIGTERM are blocked in every thread (threads inherit the mask, so this runs before
// any is started) and taken synchronously by WaitForStopSignal: no handler, no global state.
sigset_t StopSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  return signals;
}

int WaitForStopSignal(const sigset_t& signals) {
  int signal = 0;
  while (sigwait(&signals, &signal) != 0) {
  }
  return signal;
}

// The detector and the map server, or nullptr after printing why not.
std::unique_ptr<MapServer> OpenMapServer(const ServerOptions& options, const ObjmapConfig& config) {
  std::string why;
  std::unique_ptr<Detector> detector;
  if (!MakeDetector(options, config.detector, &detector, &why)) {
    std::cerr << "objmap_server: " << why << "\n";
    return nullptr;
  }
  std::unique_ptr<MapServer> map_server =
      MapServer::Open(config.map_server, options.db_path, std::move(detector), &why);
  if (!map_server) {
    std::cerr << "objmap_server: cannot open map database " << options.db_path << ": " << why
              << "\n";
  }
  return map_server;
}

// The line scripts and tests wait for; with the port actually bound (--listen HOST:0).
void PrintListening(const ServerOptions& options, int port, const MapServer& map_server) {
  const ServerStatus status = map_server.Status();
  std::printf("objmap_server listening on %s (db %s, %zu keyframes, %zu objects, version %llu)\n",
              grpc_service::AddressWithPort(options.grpc.listen_address, port).c_str(),
              options.db_path.c_str(), status.keyframes, status.objects,
              static_cast<unsigned long long>(status.map_version));
  std::fflush(stdout);
}

// The web viewer on --http, or nullptr after printing why not.
std::unique_ptr<http_viewer::HttpViewer> StartViewer(const ServerOptions& options,
                                                     const http_viewer::ViewerMap& map) {
  http_viewer::HttpViewerConfig config;
  config.listen_address = options.http_address;
  std::string why;
  if (!http_viewer::FindViewerFolder(options.viewer_folder, &config.viewer_folder, &why)) {
    std::cerr << "objmap_server: --http: " << why << "\n";
    return nullptr;
  }
  std::unique_ptr<http_viewer::HttpViewer> viewer = http_viewer::HttpViewer::Start(config, map, &why);
  if (!viewer) {
    std::cerr << "objmap_server: --http: " << why << "\n";
    return nullptr;
  }
  if (!options.grpc.tokens_path.empty()) {
    std::cerr << "objmap_server: warning: the viewer at " << viewer->url()
              << " answers without tokens: whoever reaches it reads the map\n";
  }
  std::printf("objmap_server viewer at %s\n", viewer->url().c_str());
  std::fflush(stdout);
  return viewer;
}

int Serve(const ServerOptions& options, const ObjmapConfig& config) {
  const sigset_t signals = StopSignals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::unique_ptr<MapServer> map_server = OpenMapServer(options, config);
  if (!map_server) return 1;
  grpc_service::MapServiceImpl service(*map_server);
  std::string why;
  if (!options.grpc.tokens_path.empty()) {
    grpc_service::AccessTokens tokens;
    std::string warning;
    if (!grpc_service::AccessTokens::Load(options.grpc.tokens_path, &tokens, &why, &warning)) {
      std::cerr << "objmap_server: " << why << "\n";
      return 1;
    }
    if (!warning.empty()) std::cerr << "objmap_server: warning: " << warning << "\n";
    service.RequireTokens(std::move(tokens));
  }
  if (options.grpc.ExposedWithoutProtection()) {
    std::cerr << "objmap_server: warning: serving " << options.grpc.listen_address
              << " without TLS and tokens (--insecure): anyone who reaches it can read the map, "
                 "move every pose and add objects\n";
  }
  int port = 0;
  std::unique_ptr<grpc::Server> server =
      grpc_service::StartGrpcServer(options.grpc, &service, &port, &why);
  if (!server) {
    std::cerr << "objmap_server: " << why << "\n";
    return 1;
  }
  // The viewer, when asked for; its line comes before the 'listening' line that scripts wait for.
  std::unique_ptr<http_viewer::LiveViewerMap> viewer_map;
  std::unique_ptr<http_viewer::HttpViewer> viewer;
  if (!options.http_address.empty()) {
    viewer_map = std::make_unique<http_viewer::LiveViewerMap>(*map_server,
                                                              "objmap_server " + options.db_path);
    viewer = StartViewer(options, *viewer_map);
    if (!viewer) {
      server->Shutdown();
      return 1;
    }
  }
  PrintListening(options, port, *map_server);

  const int signal = WaitForStopSignal(signals);
  std::cerr << "objmap_server: " << (signal == SIGINT ? "SIGINT" : "SIGTERM")
            << ", shutting down\n";
  // New writes are refused first (UNAVAILABLE) and watchers end; then gRPC lets running calls
  // finish; then the MapServer destructor applies what is still queued.
  map_server->Shutdown();
  if (viewer) viewer->Stop();
  server->Shutdown(std::chrono::system_clock::now() + kShutdownGrace);
  server->Wait();
  map_server.reset();
  std::cerr << "objmap_server: stopped\n";
  return 0;
}

}  // namespace
}  // namespace objmap

int main(int argc, char** argv) {
  objmap::ServerOptions options;
  std::string why;
  if (!objmap::ParseServerOptions(argc, argv, &options, &why)) {
    std::cerr << "objmap_server: " << why << "\n" << objmap::ServerUsage();
    return 2;
  }
  if (options.help) {
    std::cout << objmap::ServerUsage();
    return 0;
  }
  if (options.version) {
    std::cout << objmap::BuildDescription();
    return 0;
  }
  objmap::ObjmapConfig config;
  if (!objmap::LoadConfig(options, &config, &why)) {
    std::cerr << "objmap_server: " << why << "\n";
    return 1;
  }
  if (options.print_config) {
    std::cout << objmap::ObjmapConfigToYaml(config);
    return 0;
  }
  return objmap::Serve(options, config);
}
