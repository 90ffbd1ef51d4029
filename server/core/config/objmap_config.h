#pragma once
// objmap's one configuration: the file that objmap map, objmap_server and objmap_node all read
// (objmap.example.yaml beside this header lists every key with its default). One section per
// config struct, keys named like the struct fields. yaml-cpp stays inside objmap_config.cc, and
// this library links no transport, so every entry point can use it.

#include <string>
#include <vector>

#include "dataset/keyframe_selector.h"
#include "detection/centernet_detector.h"
#include "map_server/map_server.h"

namespace objmap {

/// Everything the configuration file sets.
struct ObjmapConfig {
  /// Sections server, store, mapper, segmenter, detection_segment, association, objects,
  /// occupancy, inventory, reassociation, regeneration. `objmap map` uses the mapper's sections
  /// (it keeps no database and queues nothing, so server and store do not apply to it).
  MapServerConfig map_server;
  /// Section keyframes: which frames of a stream become keyframes (objmap map, objmap_node; a
  /// gRPC client chooses its keyframes itself, so objmap_server does not use it).
  KeyframeSelectorConfig keyframes;
  /// Section detector: the CenterNet network. An empty model_path means the installed model
  /// (FindDetectorModel, detection/model_location.h).
  CenterNetConfig detector;

  ObjmapConfig() { detector.model_path.clear(); }

  /// Checks every section; an empty detector.model_path is allowed (the installed model).
  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Reads YAML text over `config`: keys the text sets replace the values `config` holds, the rest
/// keep them. False with a reason naming the key ("occupancy.resolution: unknown key") for
/// unknown sections or keys, values of the wrong type and malformed YAML; `config` may then be
/// partly updated. Does not call IsValid.
[[nodiscard]] bool ParseObjmapConfig(const std::string& yaml_text, ObjmapConfig* config,
                                     std::string* why);

/// ParseObjmapConfig on a file's contents, then IsValid; reasons start with the path.
[[nodiscard]] bool LoadObjmapConfig(const std::string& path, ObjmapConfig* config,
                                    std::string* why);

/// One key set from the command line: "section.key=value" (value in YAML: 0.02, true, [cup,
/// book]). False with a reason naming the key when it is malformed, unknown or mistyped.
[[nodiscard]] bool SetObjmapConfigKey(const std::string& assignment, ObjmapConfig* config,
                                      std::string* why);

/// What every entry point reads before its own flags: the file `path` (when not empty, as
/// LoadObjmapConfig) over `config`, then each "section.key=value" of `assignments` in order
/// (the --set flags; their reasons start with "--set ").
[[nodiscard]] bool ReadObjmapConfig(const std::string& path,
                                    const std::vector<std::string>& assignments,
                                    ObjmapConfig* config, std::string* why);

/// `config` as YAML in the file's layout (every key, classes by name); parses back to `config`.
[[nodiscard]] std::string ObjmapConfigToYaml(const ObjmapConfig& config);

}  // namespace objmap
