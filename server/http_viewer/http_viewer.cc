#include "http_viewer/http_viewer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "http_viewer/viewer_json.h"
#include "render/map_picture.h"
#include "types/coco_classes.h"
#include "types/install_location.h"

// cpp-httplib is a large header: this is the only file of the library that includes it. Last:
// it includes <resolv.h>, whose _res macro breaks Eigen headers included after it.
#include <httplib.h>

namespace objmap::http_viewer {

namespace fs = std::filesystem;
using nlohmann::json;

const std::vector<std::string>& ViewerFiles() {
  static const std::vector<std::string> files = {
      "index.html",
      "viewer.js",
      "viewer.css",
      "node_modules/three/build/three.module.js",
      "node_modules/three/build/three.core.js",
      "node_modules/three/examples/jsm/controls/OrbitControls.js",
  };
  return files;
}

namespace {

constexpr char kViewerFolderEnv[] = "OBJMAP_VIEWER_DIR";
constexpr char kInstallHint[] =
    "three.js is installed by `bash scripts/setup.sh` (npm ci in server/http_viewer/web); an "
    "installed objmap has it in PREFIX/share/objmap/viewer; or set OBJMAP_VIEWER_DIR, or pass "
    "the folder with --viewer-dir";

// The first file of ViewerFiles() missing in `folder`, or "" when none is.
std::string MissingFile(const std::string& folder) {
  for (const std::string& file : ViewerFiles()) {
    std::error_code error;
    if (!fs::is_regular_file(fs::path(folder) / file, error)) return file;
  }
  return "";
}

}  // namespace

bool FindViewerFolder(const std::string& configured, std::string* folder, std::string* why) {
  if (!configured.empty()) {
    const std::string missing = MissingFile(configured);
    if (missing.empty()) {
      *folder = configured;
      return true;
    }
    *why = "viewer folder " + configured + " lacks " + missing + "; " + kInstallHint;
    return false;
  }
#if defined(OBJMAP_BUILD_TREE) && defined(OBJMAP_SOURCE_VIEWER_DIR)
  const auto candidates = InstalledDataCandidates("viewer", kViewerFolderEnv, OBJMAP_BUILD_TREE,
                                                  OBJMAP_SOURCE_VIEWER_DIR);
#else
  const auto candidates = InstalledDataCandidates("viewer", kViewerFolderEnv, "", "");
#endif
  std::string looked;
  for (const DataCandidate& candidate : candidates) {
    const std::string missing = candidate.path.empty() ? "" : MissingFile(candidate.path);
    if (!candidate.path.empty() && missing.empty()) {
      *folder = candidate.path;
      return true;
    }
    looked += "\n  " + candidate.origin + ": " +
              (candidate.path.empty() ? std::string("not set")
                                      : candidate.path + " (lacks " + missing + ")");
  }
  *why = std::string("the viewer's web files were not found; looked in:") + looked + "\n" +
         kInstallHint;
  return false;
}

bool ParseListenAddress(const std::string& address, std::string* host, int* port,
                        std::string* why) {
  std::string port_text = address;
  *host = "127.0.0.1";
  if (!address.empty() && address.front() == '[') {
    const std::size_t close = address.find("]:");
    if (close == std::string::npos) {
      *why = "address " + address + ": an IPv6 host needs the form [HOST]:PORT";
      return false;
    }
    *host = address.substr(1, close - 1);
    port_text = address.substr(close + 2);
  } else if (const std::size_t colon = address.rfind(':'); colon != std::string::npos) {
    *host = address.substr(0, colon);
    port_text = address.substr(colon + 1);
    if (host->empty() || host->find(':') != std::string::npos) {
      *why = "address " + address + ": expected HOST:PORT, PORT or [IPV6]:PORT";
      return false;
    }
  }
  char* end = nullptr;
  const long value = std::strtol(port_text.c_str(), &end, 10);
  if (port_text.empty() || *end != '\0' || value < 0 || value > 65535) {
    *why = "address " + address + ": the port must be a number from 0 (any free port) to 65535";
    return false;
  }
  *port = static_cast<int>(value);
  return true;
}

bool IsLoopbackHost(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

bool HttpViewerConfig::IsValid(std::string* why) const {
  std::string host;
  int port = 0;
  if (!ParseListenAddress(listen_address, &host, &port, why)) return false;
  if (threads < 2 || threads > 256) {
    *why = "http viewer threads must be in [2, 256] (a page holds one for its long poll)";
    return false;
  }
  if (max_structure_points == 0 || default_structure_points == 0 ||
      default_structure_points > max_structure_points) {
    *why = "http viewer structure points: need 0 < default <= max";
    return false;
  }
  if (keep_alive_s < 1 || keep_alive_s > 600) {
    *why = "http viewer keep_alive_s must be in [1, 600]";
    return false;
  }
  if (max_poll_ms < 1 || max_poll_ms > 600000) {
    *why = "http viewer max_poll_ms must be in [1, 600000]";
    return false;
  }
  return true;
}

namespace {

// A request the API refuses: the status (400 or 404) and what is wrong.
struct ApiError {
  int status = 400;
  std::string message;
};

void SendJson(httplib::Response& response, const json& body, int status = 200) {
  response.status = status;
  response.set_header("Cache-Control", "no-store");
  response.set_content(body.dump(), "application/json");
}

void SendError(httplib::Response& response, const ApiError& error) {
  SendJson(response, json{{"error", error.message}}, error.status);
}

int StatusOf(const ServiceStatus& status) {
  switch (status.code) {
    case StatusCode::kOk:
      return 200;
    case StatusCode::kInvalidArgument:
      return 400;
    case StatusCode::kNotFound:
      return 404;
    case StatusCode::kResourceExhausted:
      return 429;
    case StatusCode::kUnavailable:
      return 503;
    case StatusCode::kFailedPrecondition:
      return 409;
    case StatusCode::kInternal:
      return 500;
  }
  return 500;
}

// Refuses parameters the endpoint does not take (a misspelt one would otherwise be ignored
// silently) and repeated ones.
void CheckParameters(const httplib::Request& request, const std::set<std::string>& allowed) {
  for (const auto& [name, value] : request.params) {
    if (allowed.count(name) == 0) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ApiError{400, "unknown parameter '" + name + "'; " + request.path + " takes " +
                              (list.empty() ? std::string("none") : list)};
    }
    if (request.params.count(name) > 1) throw ApiError{400, "parameter '" + name + "' given twice"};
  }
}

std::string Parameter(const httplib::Request& request, const std::string& name) {
  return request.has_param(name.c_str()) ? request.get_param_value(name.c_str()) : "";
}

// A whole-string non-negative integer in [min, max].
std::int64_t ParseInteger(const std::string& text, const std::string& name, std::int64_t min,
                          std::int64_t max) {
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || value < min || value > max) {
    throw ApiError{400, name + " must be an integer in [" + std::to_string(min) + ", " +
                            std::to_string(max) + "], not '" + text + "'"};
  }
  return value;
}

// "x,y,z" as three finite numbers.
Eigen::Vector3d ParsePoint(const std::string& text, const std::string& name) {
  Eigen::Vector3d point;
  std::size_t start = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t comma = text.find(',', start);
    if ((axis < 2) != (comma != std::string::npos)) {
      throw ApiError{400,
                     name + " must be three comma-separated numbers x,y,z, not '" + text + "'"};
    }
    const std::string part = text.substr(start, axis < 2 ? comma - start : std::string::npos);
    char* end = nullptr;
    point[axis] = std::strtod(part.c_str(), &end);
    if (part.empty() || *end != '\0' || !std::isfinite(point[axis])) {
      throw ApiError{400, name + " must be three finite numbers x,y,z, not '" + text + "'"};
    }
    start = comma + 1;
  }
  return point;
}

bool ParseBool(const std::string& text, const std::string& name) {
  if (text == "true" || text == "1") return true;
  if (text == "false" || text == "0") return false;
  throw ApiError{400, name + " must be true or false, not '" + text + "'"};
}

// The object `id_text` names in `snapshot`; 400 for a malformed id, 404 for an unknown one.
std::shared_ptr<const ObjectView> FindObject(const MapSnapshot& snapshot,
                                             const std::string& id_text) {
  const ObjectId id = ParseInteger(id_text, "object id", 1, INT64_MAX);
  // A removed object is found too: its ghost can be clicked.
  std::shared_ptr<const ObjectView> found = snapshot.ObjectOrTombstone(id);
  if (!found) {
    throw ApiError{404, "object " + id_text + " is not in the map (version " +
                            std::to_string(snapshot.version) + ")"};
  }
  return found;
}

std::string ModelBytes(const ColoredPoints& model) {
  const std::size_t n = model.points.size();
  std::string bytes(n * 15, '\0');
  char* out = bytes.data();
  for (const Eigen::Vector3f& p : model.points) {
    std::memcpy(out, p.data(), 12);
    out += 12;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<std::uint8_t, 3> rgb =
        i < model.colors.size() ? model.colors[i] : std::array<std::uint8_t, 3>{160, 160, 160};
    std::memcpy(out, rgb.data(), 3);
    out += 3;
  }
  return bytes;
}

// The colour image around `box` (a quarter of its size on each side, at least 24 px), the box
// drawn in the class colour, at most 320 px on its long side.
std::string SightingJpeg(const ColorImage& color, const ObjectSighting& sighting) {
  const cv::Mat rgb(color.height, color.width, CV_8UC3,
                    const_cast<std::uint8_t*>(color.rgb.data()));
  const BoundingBox2D& box = sighting.box;
  const float margin = std::max(24.f, 0.25f * std::max(box.Width(), box.Height()));
  const int x0 = std::clamp(static_cast<int>(std::floor(box.x_min - margin)), 0, color.width - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(box.y_min - margin)), 0, color.height - 1);
  const int x1 = std::clamp(static_cast<int>(std::ceil(box.x_max + margin)), x0 + 1, color.width);
  const int y1 = std::clamp(static_cast<int>(std::ceil(box.y_max + margin)), y0 + 1, color.height);
  cv::Mat crop;
  cv::cvtColor(rgb(cv::Rect(x0, y0, x1 - x0, y1 - y0)), crop, cv::COLOR_RGB2BGR);
  const RgbColour colour = ClassColour(std::string(ObjectClassName(sighting.class_id)));
  cv::rectangle(crop, cv::Point(static_cast<int>(box.x_min) - x0, static_cast<int>(box.y_min) - y0),
                cv::Point(static_cast<int>(box.x_max) - x0, static_cast<int>(box.y_max) - y0),
                cv::Scalar(colour[2], colour[1], colour[0]), 2);
  const int long_side = std::max(crop.cols, crop.rows);
  if (long_side > 320) {
    const double scale = 320.0 / long_side;
    cv::resize(crop, crop, cv::Size(), scale, scale, cv::INTER_AREA);
  }
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", crop, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85});
  return std::string(jpeg.begin(), jpeg.end());
}

const char* ContentType(const std::string& file) {
  if (file.size() >= 5 && file.compare(file.size() - 5, 5, ".html") == 0)
    return "text/html; charset=utf-8";
  if (file.size() >= 4 && file.compare(file.size() - 4, 4, ".css") == 0)
    return "text/css; charset=utf-8";
  return "text/javascript; charset=utf-8";
}

}  // namespace

struct HttpViewer::Impl {
  HttpViewerConfig config;
  const ViewerMap* map = nullptr;
  std::string host;
  int port = 0;
  httplib::Server server;
  std::thread thread;
  std::atomic<bool> stopping{false};
  /// Long polls waiting in Changes: at most half the threads, so that the other requests always
  /// find one.
  std::atomic<int> waiting_polls{0};
  /// URL path -> (content, type): the viewer's files, read once at start. Nothing else on disk
  /// is ever served, whatever the path asks for.
  std::map<std::string, std::pair<std::string, std::string>> files;

  void Routes();
  void Changes(const httplib::Request& request, httplib::Response& response);
  void IsFree(const httplib::Request& request, httplib::Response& response);
  void Structure(const httplib::Request& request, httplib::Response& response);
  void Sighting(const httplib::Request& request, httplib::Response& response);
};

namespace {

// Runs an API handler, answering its ApiError (or an exception) as JSON.
template <typename Handler>
httplib::Server::Handler Api(Handler handler) {
  return [handler](const httplib::Request& request, httplib::Response& response) {
    try {
      handler(request, response);
    } catch (const ApiError& error) {
      SendError(response, error);
    } catch (const std::exception& error) {
      SendError(response, {500, std::string("internal error: ") + error.what()});
    }
  };
}

}  // namespace

void HttpViewer::Impl::Routes() {
  server.Get("/api/map", Api([this](const httplib::Request& request, httplib::Response& response) {
               CheckParameters(request, {});
               SendJson(response, MapJson(*map));
             }));
  server.Get(R"(/api/objects/([^/]+))",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               CheckParameters(request, {});
               const auto snapshot = map->Snapshot();
               SendJson(response,
                        ObjectDetailJson(*snapshot, *FindObject(*snapshot, request.matches[1])));
             }));
  server.Get(R"(/api/objects/([^/]+)/model)",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               CheckParameters(request, {});
               const auto snapshot = map->Snapshot();
               const auto view = FindObject(*snapshot, request.matches[1]);
               response.set_header("Cache-Control", "no-store");
               response.set_header("X-Objmap-Version", std::to_string(snapshot->version));
               response.set_content(view->model_W ? ModelBytes(*view->model_W) : std::string(),
                                    "application/octet-stream");
             }));
  server.Get(R"(/api/objects/([^/]+)/sightings/([^/]+)\.jpg)",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               Sighting(request, response);
             }));
  server.Get("/api/structure",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               Structure(request, response);
             }));
  server.Get("/api/changes",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               Changes(request, response);
             }));
  server.Get("/api/is_free",
             Api([this](const httplib::Request& request, httplib::Response& response) {
               IsFree(request, response);
             }));
  server.Get(R"(/api/.*)", Api([](const httplib::Request& request, httplib::Response&) {
               throw ApiError{
                   404, "no such API path: " + request.path +
                            " (see /api/map, /api/objects/<id>, /api/structure, /api/changes, "
                            "/api/is_free)"};
             }));
  // Everything else: one of the viewer's own files, or 404. The table is looked up with the
  // decoded path as a whole, so "..", "%2e%2e", doubled slashes or absolute paths find nothing.
  server.Get(R"(/.*)", [this](const httplib::Request& request, httplib::Response& response) {
    const std::string path = request.path == "/" ? "/index.html" : request.path;
    const auto it = files.find(path);
    if (it == files.end()) {
      response.status = 404;
      response.set_content("404: " + request.path + " is not part of the objmap viewer\n",
                           "text/plain; charset=utf-8");
      return;
    }
    response.set_content(it->second.first, it->second.second.c_str());
  });
}

void HttpViewer::Impl::Sighting(const httplib::Request& request, httplib::Response& response) {
  CheckParameters(request, {});
  const auto view = FindObject(*map->Snapshot(), request.matches[1]);
  const KeyframeId keyframe = ParseInteger(request.matches[2], "keyframe id", 0, INT64_MAX);
  const auto sighting =
      std::find_if(view->sightings.begin(), view->sightings.end(),
                   [&](const ObjectSighting& s) { return s.keyframe_id == keyframe; });
  if (sighting == view->sightings.end()) {
    throw ApiError{404, "object " + std::to_string(view->id) + " was not seen in keyframe " +
                            std::to_string(keyframe)};
  }
  ColorImage color;
  const ServiceStatus status = map->KeyframeColor(keyframe, &color);
  if (!status.ok()) throw ApiError{StatusOf(status), status.message};
  if (color.empty() ||
      color.rgb.size() != static_cast<std::size_t>(color.width) * color.height * 3) {
    throw ApiError{404, "keyframe " + std::to_string(keyframe) + " has no colour image"};
  }
  // Not cached: another map served later on the same port has other images under the same paths.
  response.set_header("Cache-Control", "no-store");
  response.set_content(SightingJpeg(color, *sighting), "image/jpeg");
}

void HttpViewer::Impl::Structure(const httplib::Request& request, httplib::Response& response) {
  CheckParameters(request, {"max_points"});
  std::size_t max_points = config.default_structure_points;
  if (request.has_param("max_points")) {
    max_points = ParseInteger(Parameter(request, "max_points"), "max_points", 1,
                              static_cast<std::int64_t>(config.max_structure_points));
  }
  std::vector<Eigen::Vector3d> centers;
  double voxel_size_m = 0.0;
  std::uint64_t version = 0;
  const ServiceStatus status = map->StructureCenters(max_points, &centers, &voxel_size_m, &version);
  if (!status.ok()) throw ApiError{StatusOf(status), status.message};
  std::string bytes(centers.size() * 12, '\0');
  char* out = bytes.data();
  for (const Eigen::Vector3d& c : centers) {
    const Eigen::Vector3f f = c.cast<float>();
    std::memcpy(out, f.data(), 12);
    out += 12;
  }
  response.set_header("Cache-Control", "no-store");
  response.set_header("X-Objmap-Version", std::to_string(version));
  response.set_header("X-Objmap-Voxel-Size", std::to_string(voxel_size_m));
  response.set_content(std::move(bytes), "application/octet-stream");
}

void HttpViewer::Impl::Changes(const httplib::Request& request, httplib::Response& response) {
  CheckParameters(request, {"since", "timeout_ms"});
  if (!request.has_param("since")) throw ApiError{400, "since (a map version) is required"};
  const auto since =
      static_cast<std::uint64_t>(ParseInteger(Parameter(request, "since"), "since", 0, INT64_MAX));
  int timeout_ms = std::min(20000, config.max_poll_ms);
  if (request.has_param("timeout_ms")) {
    timeout_ms = static_cast<int>(
        ParseInteger(Parameter(request, "timeout_ms"), "timeout_ms", 0, config.max_poll_ms));
  }
  const int max_waiting = config.threads / 2;
  if (timeout_ms > 0 && waiting_polls.fetch_add(1) >= max_waiting) {
    waiting_polls.fetch_sub(1);
    throw ApiError{503, "too many clients follow the map (" + std::to_string(max_waiting) +
                            " long polls wait already); retry in a few seconds"};
  }
  struct Leave {
    std::atomic<int>* count;
    bool counted;
    ~Leave() {
      if (counted) count->fetch_sub(1);
    }
  } leave{&waiting_polls, timeout_ms > 0};
  // In slices, so that stopping the viewer ends a long poll within one.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  std::vector<MapChange> changes;
  do {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    changes = map->ChangesSince(
        since, std::clamp(left, std::chrono::milliseconds(0), std::chrono::milliseconds(500)));
  } while (changes.empty() && !stopping && std::chrono::steady_clock::now() < deadline);
  json list = json::array();
  for (const MapChange& change : changes) list.push_back(ChangeJson(change));
  SendJson(response, json{{"version", map->Snapshot()->version}, {"changes", list}});
}

void HttpViewer::Impl::IsFree(const httplib::Request& request, httplib::Response& response) {
  CheckParameters(request, {"min", "max", "unknown_is_free"});
  if (!request.has_param("min") || !request.has_param("max")) {
    throw ApiError{400, "min and max (x,y,z each, metres) are required"};
  }
  const Eigen::Vector3d min_W = ParsePoint(Parameter(request, "min"), "min");
  const Eigen::Vector3d max_W = ParsePoint(Parameter(request, "max"), "max");
  const bool unknown_is_free = request.has_param("unknown_is_free") &&
                               ParseBool(Parameter(request, "unknown_is_free"), "unknown_is_free");
  bool free = false;
  RegionOccupancy counts;
  std::vector<ObjectId> inside;
  std::uint64_t version = 0;
  const ServiceStatus status =
      map->IsFree(min_W, max_W, unknown_is_free, &free, &counts, &inside, &version);
  if (!status.ok()) throw ApiError{StatusOf(status), status.message};
  SendJson(response, json{{"free", free},
                          {"occupied", counts.occupied},
                          {"free_voxels", counts.free},
                          {"unknown", counts.unknown},
                          {"resolution", counts.resolution_m},
                          {"objects_inside", inside},
                          {"version", version}});
}

HttpViewer::HttpViewer() : impl_(std::make_unique<Impl>()) {}

HttpViewer::~HttpViewer() { Stop(); }

std::unique_ptr<HttpViewer> HttpViewer::Start(const HttpViewerConfig& config, const ViewerMap& map,
                                              std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  std::unique_ptr<HttpViewer> viewer(new HttpViewer());
  Impl& impl = *viewer->impl_;
  impl.config = config;
  impl.map = &map;
  for (const std::string& file : ViewerFiles()) {
    std::ifstream in(fs::path(config.viewer_folder) / file, std::ios::binary);
    if (!in) {
      *why = "viewer file " + (fs::path(config.viewer_folder) / file).string() +
             " cannot be read; " + kInstallHint;
      return nullptr;
    }
    std::ostringstream content;
    content << in.rdbuf();
    impl.files["/" + file] = {content.str(), ContentType(file)};
  }
  int port = 0;
  if (!ParseListenAddress(config.listen_address, &impl.host, &port, why)) return nullptr;
  const int threads = config.threads;
  impl.server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  impl.server.set_keep_alive_timeout(config.keep_alive_s);
  // A page on loopback is reachable from any web page the user opens (DNS rebinding): a request
  // whose Host is not this loopback address is refused.
  const bool loopback = IsLoopbackHost(impl.host);
  impl.server.set_pre_routing_handler([loopback](const httplib::Request& request,
                                                 httplib::Response& response) {
    if (!loopback) return httplib::Server::HandlerResponse::Unhandled;
    std::string host = request.get_header_value("Host");
    if (const std::size_t colon = host.rfind(':');
        colon != std::string::npos && host.find(']') == std::string::npos) {
      host = host.substr(0, colon);
    } else if (!host.empty() && host.front() == '[') {
      host = host.substr(1, host.find(']') - 1);
    }
    if (IsLoopbackHost(host)) return httplib::Server::HandlerResponse::Unhandled;
    SendError(response,
              {403, "Host '" + request.get_header_value("Host") + "' is not this loopback viewer"});
    return httplib::Server::HandlerResponse::Handled;
  });
  impl.Routes();
  if (port == 0) {
    port = impl.server.bind_to_any_port(impl.host);
  } else if (!impl.server.bind_to_port(impl.host, port)) {
    port = -1;
  }
  if (port < 0) {
    *why = "cannot listen on " + config.listen_address +
           " (in use, or not an address of this machine)";
    return nullptr;
  }
  impl.port = port;
  impl.thread = std::thread([&impl] { impl.server.listen_after_bind(); });
  return viewer;
}

std::string HttpViewer::url() const {
  const std::string& host = impl_->host;
  return "http://" + (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" +
         std::to_string(impl_->port) + "/";
}

int HttpViewer::port() const { return impl_->port; }

void HttpViewer::Stop() {
  if (!impl_ || impl_->stopping.exchange(true)) return;
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

}  // namespace objmap::http_viewer
