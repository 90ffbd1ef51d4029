#pragma once
// objmap_server's command line.

#include <string>
#include <vector>

#include "grpc_service/grpc_server.h"

namespace objmap {

struct ServerOptions {
  std::string db_path;                   ///< --db, required
  std::string config_path;               ///< --config, empty: defaults
  std::vector<std::string> config_keys;  ///< --set section.key=value, applied after the file
  std::string model_path;     ///< --model, empty: the config's (or the build's default) model
  bool no_detector = false;   ///< --no-detector
  bool print_config = false;  ///< --print-config: print the effective YAML and exit
  bool help = false;          ///< --help
  bool version = false;       ///< --version
  /// --listen, --max-message-mb, --tls-cert, --tls-key, --tls-client-ca, --tokens, --insecure
  grpc_service::GrpcServerOptions grpc;
  /// --http HOST:PORT (or PORT: loopback): the web viewer's address; empty: no viewer.
  std::string http_address;
  std::string viewer_folder;  ///< --viewer-dir, empty: found as FindViewerFolder says
};

/// Parses argv (flags as "--flag value" or "--flag=value"). False with a reason naming the flag.
[[nodiscard]] bool ParseServerOptions(int argc, const char* const* argv, ServerOptions* options,
                                      std::string* why);

/// The usage text printed by --help and after a bad command line.
[[nodiscard]] const char* ServerUsage();

}  // namespace objmap
