#include "server_options.h"

#include <cstdlib>
#include <vector>

#include "http_viewer/http_viewer.h"

namespace objmap {
namespace {

bool ParseInt(const std::string& flag, const std::string& text, int* value, std::string* why) {
  if (text.empty()) {
    *why = flag + " needs a value";
    return false;
  }
  char* end = nullptr;
  const long parsed = std::strtol(text.c_str(), &end, 10);
  if (*end != '\0' || parsed < 1 || parsed > 1 << 20) {
    *why = flag + " expects a positive integer, got '" + text + "'";
    return false;
  }
  *value = static_cast<int>(parsed);
  return true;
}

// Flags that take a value, and where it goes.
bool SetValue(const std::string& flag, const std::string& value, ServerOptions* options,
              std::string* why) {
  if (flag == "--db") {
    options->db_path = value;
  } else if (flag == "--config") {
    options->config_path = value;
  } else if (flag == "--set") {
    options->config_keys.push_back(value);
  } else if (flag == "--model") {
    options->model_path = value;
  } else if (flag == "--listen") {
    options->grpc.listen_address = value;
  } else if (flag == "--max-message-mb") {
    return ParseInt(flag, value, &options->grpc.max_receive_message_mb, why);
  } else if (flag == "--tls-cert") {
    options->grpc.tls_cert_path = value;
  } else if (flag == "--tls-key") {
    options->grpc.tls_key_path = value;
  } else if (flag == "--tls-client-ca") {
    options->grpc.tls_client_ca_path = value;
  } else if (flag == "--tokens") {
    options->grpc.tokens_path = value;
  } else if (flag == "--http") {
    options->http_address = value;
  } else if (flag == "--viewer-dir") {
    options->viewer_folder = value;
  } else {
    *why = "unknown option " + flag;
    return false;
  }
  if (value.empty()) {
    *why = flag + " needs a value";
    return false;
  }
  return true;
}

}  // namespace

bool ParseServerOptions(int argc, const char* const* argv, ServerOptions* options,
                        std::string* why) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--help" || arg == "-h") {
      options->help = true;
    } else if (arg == "--version") {
      options->version = true;
    } else if (arg == "--no-detector") {
      options->no_detector = true;
    } else if (arg == "--print-config") {
      options->print_config = true;
    } else if (arg == "--insecure") {
      options->grpc.insecure = true;
    } else if (arg.rfind("--", 0) != 0) {
      *why = "unexpected argument '" + arg + "'";
      return false;
    } else if (const std::size_t equals = arg.find('='); equals != std::string::npos) {
      if (!SetValue(arg.substr(0, equals), arg.substr(equals + 1), options, why)) return false;
    } else {
      // "--db --listen ..." is a missing value, not a database named "--listen".
      const bool has_value = i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0;
      if (!SetValue(arg, has_value ? args[i + 1] : "", options, why)) return false;
      ++i;
    }
  }
  if (options->db_path.empty() && !options->help && !options->version && !options->print_config) {
    *why = "--db PATH is required";
    return false;
  }
  // Checked here, before the database is opened and the detector loaded.
  std::string invalid;
  if (!options->grpc.IsValid(&invalid)) {
    *why = (invalid.rfind("listen address", 0) == 0 ? "--listen: "
            : invalid.rfind("max message", 0) == 0  ? "--max-message-mb: "
                                                    : "") +
           invalid;
    return false;
  }
  if (!options->http_address.empty()) {
    std::string host;
    int port = 0;
    if (!http_viewer::ParseListenAddress(options->http_address, &host, &port, &invalid)) {
      *why = "--http: " + invalid;
      return false;
    }
    // The viewer has no authentication: reachable from other machines only when asked twice.
    if (!http_viewer::IsLoopbackHost(host) && !options->grpc.insecure) {
      *why = "--http " + options->http_address +
             ": the viewer has no authentication and would show the map to anyone who reaches "
             "it; serve it on loopback (127.0.0.1:PORT, then an SSH tunnel) or add --insecure";
      return false;
    }
  }
  return true;
}

const char* ServerUsage() {
  return "objmap_server: serves an object map over gRPC (MapService, proto_srv/objmap.proto)\n"
         "while keyframes arrive, keeping it in a SQLite file.\n"
         "usage: objmap_server --db map.db [options]\n"
         "  --db PATH             SQLite map database (created when missing)\n"
         "  --listen HOST:PORT    address to serve on (default 127.0.0.1:50051; port 0 picks a\n"
         "                        free port, printed on the 'listening' line)\n"
         "  --config FILE         YAML configuration, the same file as `objmap map --config` and\n"
         "                        objmap_node's parameters "
         "(PREFIX/share/objmap/objmap.example.yaml\n"
         "                        lists every key with its default)\n"
         "  --set SECTION.KEY=V   one configuration key, after the file (repeatable)\n"
         "  --model FILE          CenterNet GraphDef for keyframes sent without detections\n"
         "                        (default: PREFIX/share/objmap/models/centernet_coco.pb, then\n"
         "                        $OBJMAP_MODEL, then the source tree's models/ for a build-tree "
         "run)\n"
         "  --no-detector         run no detector: keyframes without detections add no objects\n"
         "  --max-message-mb N    largest request accepted, MiB (default 64)\n"
         "  --tls-cert FILE       serve over TLS with this certificate chain (PEM) ...\n"
         "  --tls-key FILE        ... and its private key (PEM)\n"
         "  --tls-client-ca FILE  mutual TLS: clients need a certificate signed by this CA\n"
         "  --tokens FILE         calls need 'authorization: Bearer TOKEN'; lines 'read TOKEN'\n"
         "                        (queries) or 'write TOKEN' (also AddKeyframe, IngestKeyframes,\n"
         "                        UpdatePoses)\n"
         "  --insecure            serve an address other machines reach (0.0.0.0:50051) without\n"
         "                        TLS and tokens, or the viewer on one; refused otherwise\n"
         "  --http HOST:PORT      also serve the web viewer (the map in 3D, the inventory,\n"
         "                        keyframe crops, IsFree) at http://HOST:PORT/; PORT alone is\n"
         "                        127.0.0.1:PORT, port 0 picks a free one (printed on the\n"
         "                        'viewer at' line); off by default; read-only, no tokens, so\n"
         "                        an address other machines reach also needs --insecure\n"
         "  --viewer-dir DIR      the viewer's page and three.js (default: PREFIX/share/objmap/\n"
         "                        viewer, $OBJMAP_VIEWER_DIR, the source tree's\n"
         "                        server/http_viewer/web for a build-tree run)\n"
         "  --print-config        print the effective configuration as YAML and exit\n"
         "  --version             print the version and the build's options and exit\n"
         "Stops cleanly on SIGINT or SIGTERM: acknowledged keyframes are always durable.\n";
}

}  // namespace objmap
