#pragma once
// What the server commands of `objmap` share: the --server/--timeout options, the client, error
// reporting and the JSON form of objects.

#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "arguments.h"
#include "objmap/client.h"

namespace objmap::cli {

inline constexpr char kDefaultServer[] = "127.0.0.1:50051";

/// Exit codes of the server commands.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;  ///< the server or a file failed
inline constexpr int kExitUsage = 2;  ///< bad arguments

/// The help text lines of the options every server command takes.
inline constexpr char kServerOptionsUsage[] =
    "  --server ADDR             server address (default 127.0.0.1:50051)\n"
    "  --timeout S               deadline of each call, seconds (default 30; export 120;\n"
    "                            update-poses --wait 600; 0: none)\n"
    "  --tls-ca FILE             connect over TLS, verifying the server against this CA (PEM)\n"
    "  --tls-cert FILE           mutual TLS: this client's certificate (PEM) ...\n"
    "  --tls-key FILE            ... and its key (PEM)\n"
    "  --token-file FILE         send the bearer token in FILE (its first line) with each call\n";

/// `flags` plus --server, --timeout and the TLS and token flags.
[[nodiscard]] std::set<std::string> WithServerFlags(std::set<std::string> flags);

/// A client for --server with the --timeout deadline (`default_timeout_s` when not given).
[[nodiscard]] std::unique_ptr<MapClient> MakeClient(Arguments& args, double default_timeout_s,
                                                    const MapClientOptions& base = {});

/// Prints "objmap <command>: CODE: message" on stderr; returns kExitError.
int FailWithStatus(const std::string& command, const grpc::Status& status);
/// Prints "objmap <command>: message" on stderr; returns kExitError.
int Fail(const std::string& command, const std::string& message);
/// Prints the argument error (if any) and the usage on stderr; returns kExitUsage.
int UsageError(const Arguments& args, const std::string& usage);

/// The server's OctoMap (only `region` when it has 6 numbers) written to `path` as a .bt file;
/// messages name `command`. Returns the exit code.
int ExportOctomap(const std::string& command, MapClient* client, const std::vector<double>& region,
                  const std::string& path);
/// The server's confirmed objects (all of them with `all`; only those centred in `region` when
/// it has 6 numbers) written to `dir`: <id>_<class>.ply each and objects.json. Returns the exit
/// code.
int ExportObjects(const std::string& command, MapClient* client, const std::vector<double>& region,
                  bool all, const std::string& dir);

/// "(x, y, z)" with millimetre precision.
[[nodiscard]] std::string FormatPoint(const v1::Vec3& p);

/// JSON with keys in insertion order, so that "id" and "class" come first.
using Json = nlohmann::ordered_json;

/// A float score rounded to 4 decimals, so that JSON shows 0.61 rather than 0.6100000143.
[[nodiscard]] double Rounded(float value);

/// An object as JSON: id, class, class_id, confidence, centroid, bounds, observations,
/// keyframes, confirmed, changed_version, scores (the point model is left out).
[[nodiscard]] Json ObjectJson(const v1::Object& object);

}  // namespace objmap::cli
