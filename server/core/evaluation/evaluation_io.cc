#include "evaluation/evaluation_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "pointcloud_io/pointcloud_io.h"
#include "types/coco_classes.h"
#include "types/frame.h"

namespace objmap {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

bool ParseFile(const std::string& path, Json* document, std::string* why) {
  std::ifstream in(path);
  if (!in) {
    *why = path + ": cannot be opened";
    return false;
  }
  *document = Json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (document->is_discarded()) {
    *why = path + ": not valid JSON";
    return false;
  }
  return true;
}

// The "objects" array of a file's top-level object.
bool ParseObjectsArray(const std::string& path, Json* document, std::string* why) {
  if (!ParseFile(path, document, why)) return false;
  if (!document->is_object() || !document->contains("objects") ||
      !(*document)["objects"].is_array()) {
    *why = path + ": \"objects\" (an array) is missing";
    return false;
  }
  return true;
}

// The "class" of an entry: a COCO class, or also "unknown" (a map's unnamed objects) when
// `allow_unknown`.
bool ClassOf(const Json& entry, const std::string& where, bool allow_unknown, int* class_id,
             std::string* why) {
  if (!entry.contains("class") || !entry["class"].is_string()) {
    *why = where + ": \"class\" (a COCO class name) is missing";
    return false;
  }
  const std::string name = entry["class"].get<std::string>();
  *class_id = allow_unknown ? ObjectClassId(name) : CocoClassId(name);
  if (*class_id < 0) {
    *why = where + ": class '" + entry["class"].get<std::string>() + "' is not a COCO class";
    return false;
  }
  return true;
}

// An array of `n` finite numbers.
bool Numbers(const Json& value, std::size_t n, std::vector<double>* out) {
  if (!value.is_array() || value.size() != n) return false;
  out->clear();
  for (const Json& v : value) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) return false;
    out->push_back(v.get<double>());
  }
  return true;
}

bool Vector3(const Json& value, Eigen::Vector3d* v) {
  std::vector<double> xyz;
  if (!Numbers(value, 3, &xyz)) return false;
  *v = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  return true;
}

bool ReadGroundTruthObject(const Json& entry, const std::string& where, GroundTruthObject* object,
                           std::string* why) {
  if (!entry.is_object() || !entry.contains("id") || !entry["id"].is_number_integer()) {
    *why = where + ": \"id\" (an integer) is missing";
    return false;
  }
  object->id = entry["id"].get<int>();
  if (!ClassOf(entry, where, /*allow_unknown=*/false, &object->class_id, why)) return false;
  std::vector<double> pose;
  if (!entry.contains("pose") || !Numbers(entry["pose"], 16, &pose)) {
    *why = where + ": \"pose\" must be 16 finite numbers (a 4x4 transform, row by row)";
    return false;
  }
  Eigen::Matrix4d T;
  for (int i = 0; i < 16; ++i) T(i / 4, i % 4) = pose[i];
  std::string reason;
  if (!IsValidRigidTransform(T, &reason)) {
    *why = where + ": pose: " + reason;
    return false;
  }
  object->T_W_B.matrix() = T;
  if (!entry.contains("size") || !Vector3(entry["size"], &object->size_m) ||
      (object->size_m.array() < 0.0).any()) {
    *why = where + ": \"size\" must be 3 finite numbers >= 0 (metres)";
    return false;
  }
  if (entry.contains("visible_frames")) {
    const Json& frames = entry["visible_frames"];
    if (!frames.is_number_integer() || frames.get<long long>() < 0) {
      *why = where + ": \"visible_frames\" must be an integer >= 0";
      return false;
    }
    object->visible_frames = static_cast<int>(
        std::min<long long>(frames.get<long long>(), std::numeric_limits<int>::max()));
  }
  if (entry.contains("surface_sample")) {
    const Json& sample = entry["surface_sample"];
    for (std::size_t i = 0; sample.is_array() && i < sample.size(); ++i) {
      Eigen::Vector3d p;
      if (!Vector3(sample[i], &p)) {
        *why = where + ": surface_sample[" + std::to_string(i) + "] is not 3 finite numbers";
        return false;
      }
      object->surface_W.push_back(p.cast<float>());
    }
    if (!sample.is_array()) {
      *why = where + ": \"surface_sample\" must be an array of [x, y, z]";
      return false;
    }
  }
  if (entry.contains("surface_mesh")) {
    const Json& mesh = entry["surface_mesh"];
    if (!mesh.is_object() || !mesh.contains("vertices") || !mesh.contains("triangles") ||
        !mesh["vertices"].is_array() || !mesh["triangles"].is_array()) {
      *why = where + ": \"surface_mesh\" must hold \"vertices\" [[x, y, z], ...] and " +
             "\"triangles\" [[i, j, k], ...]";
      return false;
    }
    const Json& vertices = mesh["vertices"];
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      Eigen::Vector3d p;
      if (!Vector3(vertices[i], &p)) {
        *why = where + ": surface_mesh vertex " + std::to_string(i) + " is not 3 finite numbers";
        return false;
      }
      object->mesh_vertices_W.push_back(p.cast<float>());
    }
    const Json& triangles = mesh["triangles"];
    const auto vertex_count = static_cast<std::int64_t>(vertices.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
      const Json& t = triangles[i];
      bool valid = t.is_array() && t.size() == 3;
      Eigen::Vector3i corners = Eigen::Vector3i::Zero();
      for (int k = 0; valid && k < 3; ++k) {
        valid = t[k].is_number_integer() && t[k].get<std::int64_t>() >= 0 &&
                t[k].get<std::int64_t>() < vertex_count;
        if (valid) corners[k] = t[k].get<int>();
      }
      if (!valid) {
        *why = where + ": surface_mesh triangle " + std::to_string(i) +
               " is not 3 indices of its vertices";
        return false;
      }
      object->mesh_triangles.push_back(corners);
    }
  }
  return true;
}

// One object of objects.json: from `objmap map` ("confirmed", "in_inventory",
// "bbox_min"/"bbox_max") or from `objmap export` ("confirmed", "bounds": {"min", "max"}, "ply").
// `claimed` false: not one the map lists in its inventory.
bool ReadMappedObject(const Json& entry, const fs::path& dir, const std::string& where,
                      MappedObject* object, bool* claimed, std::string* why) {
  if (!entry.is_object() || !entry.contains("id") || !entry["id"].is_number_integer()) {
    *why = where + ": \"id\" (an integer) is missing";
    return false;
  }
  object->id = entry["id"].get<ObjectId>();
  if (!ClassOf(entry, where, /*allow_unknown=*/true, &object->class_id, why)) return false;
  const bool from_map = entry.contains("in_inventory");
  // Confirmed objects are the map's claims, unknown ones too (they are counted apart); older
  // `objmap map` outputs mark only "in_inventory".
  *claimed = entry.value("confirmed", from_map && entry.value("in_inventory", false));
  const bool bounds_ok =
      Vector3(entry.value("centroid", Json()), &object->centroid_W) &&
      (from_map ? Vector3(entry.value("bbox_min", Json()), &object->min_W) &&
                      Vector3(entry.value("bbox_max", Json()), &object->max_W)
                : entry.contains("bounds") &&
                      Vector3(entry["bounds"].value("min", Json()), &object->min_W) &&
                      Vector3(entry["bounds"].value("max", Json()), &object->max_W));
  if (!bounds_ok) {
    *why = where + ": centroid and bounds must be 3 finite numbers each";
    return false;
  }
  if (!*claimed) return true;
  const fs::path ply = from_map
                           ? dir / "objects" / ObjectModelFileName(object->id, object->class_id)
                           : dir / entry.value("ply", std::string());
  std::error_code error;
  if (!fs::is_regular_file(ply, error)) return true;  // no model: no model accuracy
  std::vector<std::array<std::uint8_t, 3>> colors;
  return ReadPly(ply.string(), &object->model_W, &colors, why);
}

// A change file's "format": the simulator's and the map's files look alike, and one given for
// the other must be refused, not scored.
bool CheckFormat(const Json& document, const std::string& path, const std::string& format,
                 std::string* why) {
  if (!document.is_object()) {
    *why = path + ": expected a JSON object with \"format\": \"" + format + "\"";
    return false;
  }
  if (!document.contains("format") || !document["format"].is_string()) {
    *why = path + ": \"format\" (\"" + format + "\") is missing";
    return false;
  }
  const std::string found = document["format"].get<std::string>();
  if (found != format) {
    *why = path + ": \"format\" is '" + found + "', expected '" + format + "'";
    return false;
  }
  return true;
}

bool PlaceOf(const Json& entry, const char* field, const std::string& where, Eigen::Vector3d* v,
             std::string* why) {
  if (!entry.contains(field) || !Vector3(entry[field], v)) {
    *why = where + ": \"" + field + "\" must be 3 finite numbers (metres)";
    return false;
  }
  return true;
}

bool ReadGroundTruthChange(const Json& entry, ChangeKind kind, const std::string& where,
                           GroundTruthChange* change, std::string* why) {
  if (!entry.is_object() || !entry.contains("id") || !entry["id"].is_number_integer()) {
    *why = where + ": \"id\" (an integer) is missing";
    return false;
  }
  change->kind = kind;
  change->id = entry["id"].get<int>();
  if (!ClassOf(entry, where, /*allow_unknown=*/false, &change->class_id, why)) return false;
  if (kind != ChangeKind::kMoved) {
    return PlaceOf(entry, "position", where, &change->position_W, why);
  }
  return PlaceOf(entry, "from", where, &change->from_W, why) &&
         PlaceOf(entry, "to", where, &change->position_W, why);
}

bool KindOf(const Json& entry, const std::string& where, ChangeKind* kind, std::string* why) {
  if (entry.contains("kind") && entry["kind"].is_string()) {
    for (ChangeKind k : kChangeKinds) {
      if (entry["kind"].get<std::string>() == ChangeKindName(k)) {
        *kind = k;
        return true;
      }
    }
  }
  *why = where + ": \"kind\" must be \"added\", \"removed\" or \"moved\"";
  return false;
}

bool IntegerOf(const Json& entry, const char* field, const std::string& where, std::int64_t* value,
               std::string* why) {
  if (!entry.contains(field)) {
    *why = where + ": \"" + field + "\" (an integer) is missing";
    return false;
  }
  if (!entry[field].is_number_integer()) {
    *why = where + ": \"" + field + "\" must be an integer";
    return false;
  }
  *value = entry[field].get<std::int64_t>();
  return true;
}

bool ReadReportedChange(const Json& entry, const std::string& where, ReportedChange* change,
                        std::string* why) {
  if (!entry.is_object()) {
    *why = where + ": expected an object";
    return false;
  }
  if (!KindOf(entry, where, &change->kind, why) ||
      !IntegerOf(entry, "object_id", where, &change->object_id, why) ||
      !ClassOf(entry, where, /*allow_unknown=*/true, &change->class_id, why) ||
      !PlaceOf(entry, "position", where, &change->position_W, why)) {
    return false;
  }
  // A map that knows no sessions writes none; --since-session then has nothing to go by.
  if (entry.contains("session_id") &&
      !IntegerOf(entry, "session_id", where, &change->session_id, why)) {
    return false;
  }
  if (change->kind == ChangeKind::kMoved && !PlaceOf(entry, "from", where, &change->from_W, why)) {
    return false;
  }
  if (entry.contains("keyframe_id") &&
      !IntegerOf(entry, "keyframe_id", where, &change->keyframe_id, why)) {
    return false;
  }
  if (entry.contains("stamp")) {
    if (!entry["stamp"].is_number() || !std::isfinite(entry["stamp"].get<double>())) {
      *why = where + ": \"stamp\" must be a finite number (seconds)";
      return false;
    }
    change->stamp = entry["stamp"].get<double>();
  }
  if (entry.contains("min") || entry.contains("max")) {
    return PlaceOf(entry, "min", where, &change->min_W, why) &&
           PlaceOf(entry, "max", where, &change->max_W, why);
  }
  return true;
}

}  // namespace

bool ReadGroundTruth(const std::string& path, std::vector<GroundTruthObject>* objects,
                     std::string* why) {
  objects->clear();
  Json document;
  if (!ParseObjectsArray(path, &document, why)) return false;
  const Json& entries = document["objects"];
  for (std::size_t i = 0; i < entries.size(); ++i) {
    GroundTruthObject object;
    if (!ReadGroundTruthObject(entries[i], path + ": objects[" + std::to_string(i) + "]", &object,
                               why)) {
      return false;
    }
    objects->push_back(std::move(object));
  }
  return true;
}

bool ReadSeenSurface(const std::string& ground_truth_path, SeenSurface* surface, bool* present,
                     std::string* why) {
  *present = false;
  Json document;
  if (!ParseFile(ground_truth_path, &document, why)) return false;
  if (!document.is_object() || !document.contains("seen_surface")) return true;
  const Json& entry = document["seen_surface"];
  const std::string where = ground_truth_path + ": seen_surface";
  if (!entry.is_object() || !entry.contains("voxel_size_m") || !entry["voxel_size_m"].is_number() ||
      !(entry["voxel_size_m"].get<double>() > 0.0) || !entry.contains("structure") ||
      !entry["structure"].is_string() || !entry.contains("objects") ||
      !entry["objects"].is_string()) {
    *why = where + ": needs \"voxel_size_m\" (> 0), \"structure\" and \"objects\" (PLY paths)";
    return false;
  }
  surface->voxel_size_m = entry["voxel_size_m"].get<double>();
  const fs::path dir = fs::path(ground_truth_path).parent_path();
  std::vector<std::array<std::uint8_t, 3>> colors;
  if (!ReadPly((dir / entry["structure"].get<std::string>()).string(), &surface->structure_W,
               &colors, why) ||
      !ReadPly((dir / entry["objects"].get<std::string>()).string(), &surface->objects_W, &colors,
               why)) {
    *why = where + ": " + *why;
    return false;
  }
  *present = true;
  return true;
}

bool ReadExpectedCounts(const std::string& path, std::map<int, CountRange>* counts,
                        std::string* why) {
  counts->clear();
  Json document;
  if (!ParseFile(path, &document, why)) return false;
  if (!document.is_object()) {
    *why = path + ": expected an object of class: count or class: [min, max]";
    return false;
  }
  for (const auto& [name, value] : document.items()) {
    const int class_id = CocoClassId(name);
    if (class_id < 0) {
      *why = path + ": '" + name + "' is not a COCO class";
      return false;
    }
    CountRange range;
    if (value.is_number_unsigned()) {
      range.min = range.max = value.get<int>();
    } else if (value.is_array() && value.size() == 2 && value[0].is_number_unsigned() &&
               value[1].is_number_unsigned() && value[0].get<int>() <= value[1].get<int>()) {
      range.min = value[0].get<int>();
      range.max = value[1].get<int>();
    } else {
      *why = path + ": " + name + ": expected a count >= 0 or a range [min, max]";
      return false;
    }
    (*counts)[class_id] = range;
  }
  return true;
}

bool ReadMapDirectory(const std::string& dir, std::vector<MappedObject>* objects,
                      std::string* why) {
  objects->clear();
  const std::string path = (fs::path(dir) / "objects.json").string();
  Json document;
  if (!ParseObjectsArray(path, &document, why)) return false;
  const Json& entries = document["objects"];
  for (std::size_t i = 0; i < entries.size(); ++i) {
    MappedObject object;
    bool claimed = false;
    if (!ReadMappedObject(entries[i], dir, path + ": objects[" + std::to_string(i) + "]", &object,
                          &claimed, why)) {
      return false;
    }
    if (claimed) objects->push_back(std::move(object));
  }
  return true;
}

bool ReadGroundTruthChanges(const std::string& path, std::vector<GroundTruthChange>* changes,
                            std::string* why) {
  changes->clear();
  Json document;
  if (!ParseFile(path, &document, why) || !CheckFormat(document, path, "objmap-changes-1", why)) {
    return false;
  }
  for (ChangeKind kind : kChangeKinds) {
    const std::string name(ChangeKindName(kind));
    if (!document.contains(name)) continue;  // nothing of this kind changed
    const Json& entries = document[name];
    if (!entries.is_array()) {
      *why = path + ": \"" + name + "\" must be an array";
      return false;
    }
    for (std::size_t i = 0; i < entries.size(); ++i) {
      GroundTruthChange change;
      const std::string where = path + ": " + name + "[" + std::to_string(i) + "]";
      if (!ReadGroundTruthChange(entries[i], kind, where, &change, why)) {
        return false;
      }
      changes->push_back(change);
    }
  }
  return true;
}

bool ReadReportedChanges(const std::string& path, std::vector<ReportedChange>* changes,
                         std::string* why) {
  changes->clear();
  Json document;
  if (!ParseFile(path, &document, why) ||
      !CheckFormat(document, path, "objmap-map-changes-1", why)) {
    return false;
  }
  if (!document.contains("changes") || !document["changes"].is_array()) {
    *why = path + ": \"changes\" (an array) is missing";
    return false;
  }
  const Json& entries = document["changes"];
  for (std::size_t i = 0; i < entries.size(); ++i) {
    ReportedChange change;
    if (!ReadReportedChange(entries[i], path + ": changes[" + std::to_string(i) + "]", &change,
                            why)) {
      return false;
    }
    changes->push_back(change);
  }
  return true;
}

}  // namespace objmap
