#pragma once
// The JSON the viewer's API answers with: the map (inventory, objects, tombstones, the places
// moved objects stood before, the sessions), one object's details and the map's changes.

#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "http_viewer/viewer_map.h"

namespace objmap::http_viewer {

/// "#rrggbb" of a class's colour (the rendered picture's).
[[nodiscard]] std::string HexColour(const std::string& class_name);
/// The ids the inventory counts.
[[nodiscard]] std::set<ObjectId> InventoryObjects(const MapSnapshot& snapshot);
/// /api/map: source, up, version, keyframes, inventory, objects (each with its state and
/// previous places), tombstones (removed objects, as last seen) and the sessions the objects'
/// sightings and changes name.
[[nodiscard]] nlohmann::json MapJson(const ViewerMap& map);
/// /api/objects/ID: the summary with scores and sightings.
[[nodiscard]] nlohmann::json ObjectDetailJson(const MapSnapshot& snapshot, const ObjectView& view);
/// One entry of /api/changes.
[[nodiscard]] nlohmann::json ChangeJson(const MapChange& change);

}  // namespace objmap::http_viewer
