#pragma once
// objmap_server's YAML configuration: one section per config struct, keys named like the struct
// fields (see objmap.example.yaml). yaml-cpp stays inside server_config.cc.

#include <string>

#include "detection/centernet_detector.h"
#include "map_server/map_server.h"

namespace objmap {

/// Everything objmap_server reads from its configuration file.
struct ServerConfig {
  /// Sections server, store, mapper, segmenter, detection_segment, association, objects,
  /// occupancy, inventory.
  MapServerConfig map_server;
  /// Section detector (used unless objmap_server runs with --no-detector).
  CenterNetConfig detector;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Reads YAML text over `config`: keys the text sets replace the values `config` holds, the rest
/// keep them. False with a reason naming the key ("occupancy.resolution: unknown key") for
/// unknown sections or keys, values of the wrong type and malformed YAML; `config` may then be
/// partly updated. Does not call IsValid.
[[nodiscard]] bool ParseServerConfig(const std::string& yaml_text, ServerConfig* config,
                                     std::string* why);

/// ParseServerConfig on a file's contents, then IsValid; reasons start with the path.
[[nodiscard]] bool LoadServerConfig(const std::string& path, ServerConfig* config,
                                    std::string* why);

/// `config` as YAML in the file's layout (every key, classes by name); parses back to `config`.
[[nodiscard]] std::string ServerConfigToYaml(const ServerConfig& config);

}  // namespace objmap
