// `objmap view`: the web viewer on a map folder, served locally until Ctrl-C.
#include <csignal>
#include <iostream>

#include "arguments.h"
#include "commands.h"
#include "http_viewer/http_viewer.h"
#include "http_viewer/viewer_map.h"

namespace objmap::cli {
namespace {

constexpr char kViewUsage[] =
    "objmap view: shows a map folder in the browser: the structure and the objects in 3D, the\n"
    "inventory, each object's class scores and the keyframe crops that saw it, IsFree for a box.\n"
    "usage: objmap view <map-dir> [options]\n"
    "  <map-dir>            written by `objmap map --out` (map.bt, objects.json, objects/*.ply,\n"
    "                       keyframes.txt, keyframes/*.jpg)\n"
    "  --http HOST:PORT     where to serve (default 127.0.0.1:8480; PORT alone: loopback;\n"
    "                       port 0 picks a free one); the URL is printed\n"
    "  --insecure           allow an address other machines reach (the viewer has no\n"
    "                       authentication)\n"
    "  --viewer-dir DIR     the page and three.js (default: PREFIX/share/objmap/viewer,\n"
    "                       $OBJMAP_VIEWER_DIR, the source tree's for a build-tree run)\n"
    "Serves until Ctrl-C (SIGINT) or SIGTERM.\n";

}  // namespace

int RunViewCommand(int argc, char** argv) {
  Arguments args(argc, argv, {"--http", "--viewer-dir"}, {"--help", "--insecure"});
  if (args.Has("--help")) {
    std::cout << kViewUsage;
    return 0;
  }
  http_viewer::HttpViewerConfig config;
  config.listen_address = args.Get("--http", config.listen_address);
  std::string host, why;
  int port = 0;
  if (args.error().empty() &&
      !http_viewer::ParseListenAddress(config.listen_address, &host, &port, &why)) {
    args.SetError("--http: " + why);
  }
  if (args.error().empty() && !http_viewer::IsLoopbackHost(host) && !args.Has("--insecure")) {
    args.SetError("--http " + config.listen_address +
                  ": the viewer has no authentication; serve it on loopback or add --insecure");
  }
  if (!args.error().empty() || args.positional().size() != 1) {
    std::cerr << (args.error().empty() ? "objmap view: expected one map folder\n"
                                       : "objmap view: " + args.error() + "\n")
              << kViewUsage;
    return 2;
  }
  // SIGINT and SIGTERM are taken synchronously below, blocked before the server's threads start
  // (they inherit the mask).
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const std::string dir = args.positional()[0];
  std::unique_ptr<http_viewer::FolderViewerMap> map = http_viewer::FolderViewerMap::Open(dir, &why);
  if (!map || !http_viewer::FindViewerFolder(args.Get("--viewer-dir", ""), &config.viewer_folder,
                                             &why)) {
    std::cerr << "objmap view: " << why << "\n";
    return 1;
  }
  std::unique_ptr<http_viewer::HttpViewer> viewer = http_viewer::HttpViewer::Start(config, *map, &why);
  if (!viewer) {
    std::cerr << "objmap view: " << why << "\n";
    return 1;
  }
  const auto snapshot = map->Snapshot();
  std::cout << "objmap view: " << dir << " (" << snapshot->objects.size() << " objects, "
            << snapshot->num_keyframes << " keyframes) at " << viewer->url()
            << " (Ctrl-C stops)" << std::endl;
  int signal = 0;
  while (sigwait(&signals, &signal) != 0) {
  }
  viewer->Stop();
  std::cout << "objmap view: stopped" << std::endl;
  return 0;
}

}  // namespace objmap::cli
