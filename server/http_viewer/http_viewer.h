#pragma once
// The web viewer: an HTTP server (cpp-httplib) that serves the viewer's page, three.js and a
// read-only JSON/binary API over a ViewerMap. Bound to loopback unless told otherwise.
//
// API (every answer JSON unless said; errors {"error": "..."} with 400 or 404):
//   GET /api/map                      version, keyframes, inventory, every object (no model)
//   GET /api/objects/<id>             one object with its class scores and sightings
//   GET /api/objects/<id>/model       its 5 mm model: float32 x y z per point, then r g b bytes
//   GET /api/objects/<id>/sightings/<keyframe>.jpg
//                                     the keyframe's colour image around the detection, boxed
//   GET /api/structure?max_points=N   occupied voxel centres, float32 x y z each
//   GET /api/changes?since=V&timeout_ms=T
//                                     the map's changes after version V (long poll, up to T)
//   GET /api/is_free?min=X,Y,Z&max=X,Y,Z&unknown_is_free=true|false

#include <memory>
#include <string>
#include <vector>

#include "http_viewer/viewer_map.h"

namespace objmap::http_viewer {

/// The files the page needs, relative to the viewer folder: the page itself and three.js as npm
/// installs it (scripts/setup.sh); nothing else in the folder is ever served.
[[nodiscard]] const std::vector<std::string>& ViewerFiles();

/// The viewer folder: `configured` when not empty, else the first of PREFIX/share/objmap/viewer,
/// $OBJMAP_VIEWER_DIR and (for a build-tree executable) the source tree's server/http_viewer/web
/// that holds every ViewerFiles() entry. False with a reason naming the places and what is missing.
[[nodiscard]] bool FindViewerFolder(const std::string& configured, std::string* folder,
                                    std::string* why);

struct HttpViewerConfig {
  /// HOST:PORT (PORT 0: any free port). A host other than loopback exposes the map (read-only)
  /// to the network; objmap_server warns about it.
  std::string listen_address = "127.0.0.1:8480";
  std::string viewer_folder;  ///< holds ViewerFiles(); FindViewerFolder
  /// Request threads. A connection holds one while it is open (a browser opens up to six per
  /// page, one of them in a long poll), so a few pages fit before requests queue.
  int threads = 16;
  /// An idle kept-alive connection is closed after this long, freeing its thread.
  int keep_alive_s = 2;
  /// Most structure points one request returns, and the default.
  std::size_t max_structure_points = 4000000;
  std::size_t default_structure_points = 600000;
  /// Longest long poll of /api/changes, milliseconds.
  int max_poll_ms = 30000;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Splits HOST:PORT ("8480" alone: 127.0.0.1:8480; "[::1]:8480" for IPv6). False with a reason.
[[nodiscard]] bool ParseListenAddress(const std::string& address, std::string* host, int* port,
                                      std::string* why);
/// True for 127.0.0.0/8, ::1 and "localhost".
[[nodiscard]] bool IsLoopbackHost(const std::string& host);

/// The running viewer. Thread-safety: Stop may be called from any thread.
class HttpViewer {
 public:
  /// Binds and starts serving `map` (which must outlive this) on threads of its own. nullptr
  /// with the reason when the config is invalid, a viewer file is missing or the address
  /// cannot be bound.
  static std::unique_ptr<HttpViewer> Start(const HttpViewerConfig& config, const ViewerMap& map,
                                           std::string* why);
  /// Stops serving (ends long polls within about half a second).
  ~HttpViewer();
  HttpViewer(const HttpViewer&) = delete;
  HttpViewer& operator=(const HttpViewer&) = delete;

  /// The page's address, http://HOST:PORT/ with the port actually bound.
  [[nodiscard]] std::string url() const;
  [[nodiscard]] int port() const;
  void Stop();

 private:
  HttpViewer();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::http_viewer
