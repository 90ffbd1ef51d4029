#include "config/objmap_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>

#include "config/config_fields.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

template <typename T>
const char* Expected() {
  if constexpr (std::is_same_v<T, bool>) return "true or false";
  if constexpr (std::is_integral_v<T>) return "an integer";
  if constexpr (std::is_floating_point_v<T>) return "a number";
  return "a string";
}

std::string Describe(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  return node.IsSequence() ? "a list" : node.IsMap() ? "a mapping" : "nothing";
}

// The first key of `map` that `known` lacks or that comes twice (then `twice` is set).
std::optional<std::string> BadKey(const YAML::Node& map, const std::vector<std::string>& known,
                                  bool* twice) {
  std::set<std::string> seen;
  for (const auto& entry : map) {
    const std::string key = entry.first.as<std::string>();
    *twice = !seen.insert(key).second;
    if (*twice || std::find(known.begin(), known.end(), key) == known.end()) return key;
  }
  return std::nullopt;
}

std::string Join(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// Reads the keys of each section from the YAML tree; stops at the first problem.
class Reader {
 public:
  explicit Reader(const YAML::Node& root) : root_(root) {}

  void Section(const char* name) {
    FinishSection();
    sections_.push_back(name);
    section_name_ = name;
    keys_.clear();
    // Nodes are handles whose assignment writes through, so the section is re-created instead.
    section_.reset();
    if (root_.IsMap()) section_.emplace(root_[name]);
    if (ok() && HasSection() && !section_->IsNull() && !section_->IsMap()) {
      error_ = section_name_ + ": expected a mapping of keys, got " + Describe(*section_);
    }
  }

  template <typename T>
  void operator()(const char* key, T* value) {
    const YAML::Node node = Field(key);
    if (!node) return;
    try {
      *value = node.as<T>();
    } catch (const YAML::Exception&) {
      error_ =
          section_name_ + "." + key + ": expected " + Expected<T>() + ", got " + Describe(node);
    }
  }

  void operator()(const char* key, PoseSource* source) {
    const YAML::Node node = Field(key);
    if (!node) return;
    if (!node.IsScalar() || !ParsePoseSource(node.Scalar(), source)) {
      error_ = section_name_ + "." + key + ": expected request, estimate or session_frame, got " + Describe(node);
    }
  }

  /// COCO classes, by name ("dining table") or id.
  void operator()(const char* key, std::vector<int>* class_ids) {
    const YAML::Node node = Field(key);
    if (!node) return;
    const std::string field = section_name_ + "." + key;
    if (!node.IsSequence()) {
      error_ = field + ": expected a list of COCO class names, got " + Describe(node);
      return;
    }
    std::vector<int> ids;
    for (std::size_t i = 0; i < node.size() && ok(); ++i) {
      const std::string name = node[i].IsScalar() ? node[i].Scalar() : "";
      int id = CocoClassId(name);
      if (id < 0) id = ClassIdFromNumber(name);
      if (id < 0) {
        error_ =
            field + "[" + std::to_string(i) + "]: " + Describe(node[i]) + " is not a COCO class";
      }
      ids.push_back(id);
    }
    if (ok()) *class_ids = ids;
  }

  void Finish() {
    FinishSection();
    if (!ok() || !root_.IsMap()) return;
    bool twice = false;
    if (const auto name = BadKey(root_, sections_, &twice)) {
      error_ = twice ? "section '" + *name + "' appears twice"
                     : "unknown section '" + *name + "' (sections: " + Join(sections_) + ")";
    }
  }

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  // The value of `key` in the current section, or an undefined node.
  YAML::Node Field(const char* key) {
    keys_.push_back(key);
    if (!ok() || !HasSection() || !section_->IsMap()) {
      return YAML::Node(YAML::NodeType::Undefined);
    }
    const YAML::Node& section = *section_;
    return section[key];
  }

  [[nodiscard]] bool HasSection() const { return section_ && section_->IsDefined(); }

  static int ClassIdFromNumber(const std::string& text) {
    std::istringstream stream(text);
    int id = -1;
    if (!(stream >> id) || !stream.eof() || id < 0 || id >= kNumCocoClasses) return -1;
    return id;
  }

  void FinishSection() {
    if (!ok() || !HasSection() || !section_->IsMap()) return;
    bool twice = false;
    if (const auto key = BadKey(*section_, keys_, &twice)) {
      error_ = section_name_ + "." + *key +
               (twice ? ": appears twice"
                      : ": unknown key (" + section_name_ + " has: " + Join(keys_) + ")");
    }
  }

  const YAML::Node root_;
  std::optional<YAML::Node> section_;
  std::string section_name_;
  std::vector<std::string> keys_;
  std::vector<std::string> sections_;
  std::string error_;
};

// Emits every section and key.
class Writer {
 public:
  Writer() {
    out_.SetFloatPrecision(6);  // round-trips the decimals people write, without float noise
    out_.SetDoublePrecision(15);
    out_ << YAML::BeginMap;
  }

  void Section(const char* name) {
    if (in_section_) out_ << YAML::EndMap;
    out_ << YAML::Key << name << YAML::Value << YAML::BeginMap;
    in_section_ = true;
  }

  template <typename T>
  void operator()(const char* key, T* value) {
    out_ << YAML::Key << key << YAML::Value << *value;
  }

  void operator()(const char* key, PoseSource* source) {
    out_ << YAML::Key << key << YAML::Value << std::string(PoseSourceName(*source));
  }

  void operator()(const char* key, std::vector<int>* class_ids) {
    out_ << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int id : *class_ids) out_ << std::string(CocoClassName(id));
    out_ << YAML::EndSeq;
  }

  void Finish() {
    if (in_section_) out_ << YAML::EndMap;
    out_ << YAML::EndMap;
    in_section_ = false;
  }

  [[nodiscard]] std::string Text() const { return std::string(out_.c_str()) + "\n"; }

 private:
  YAML::Emitter out_;
  bool in_section_ = false;
};

}  // namespace

bool ObjmapConfig::IsValid(std::string* why) const {
  if (!map_server.IsValid(why)) return false;
  std::string reason;
  if (!keyframes.IsValid(&reason)) {
    *why = "keyframes: " + reason;
    return false;
  }
  // An empty model path is a request for the installed model, found when the detector is made.
  CenterNetConfig detector_checked = detector;
  if (detector_checked.model_path.empty()) detector_checked.model_path = "(installed model)";
  return detector_checked.IsValid(why);
}

bool ParseObjmapConfig(const std::string& yaml_text, ObjmapConfig* config, std::string* why) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    *why = e.what();
    return false;
  }
  if (!root.IsNull() && !root.IsMap()) {
    *why = "expected a mapping of sections at the top level, got " + Describe(root);
    return false;
  }
  Reader reader(root);
  try {
    internal::VisitObjmapConfig(config, reader);
  } catch (const YAML::Exception& e) {  // e.g. a key that is itself a list
    *why = e.what();
    return false;
  }
  if (!reader.ok()) *why = reader.error();
  return reader.ok();
}

bool LoadObjmapConfig(const std::string& path, ObjmapConfig* config, std::string* why) {
  std::ifstream file(path);
  if (!file) {
    *why = path + ": cannot open the configuration file";
    return false;
  }
  std::ostringstream text;
  text << file.rdbuf();
  std::string reason;
  if (!ParseObjmapConfig(text.str(), config, &reason) || !config->IsValid(&reason)) {
    *why = path + ": " + reason;
    return false;
  }
  return true;
}

bool SetObjmapConfigKey(const std::string& assignment, ObjmapConfig* config, std::string* why) {
  const std::size_t equals = assignment.find('=');
  const std::size_t dot = assignment.find('.');
  const bool has_section_and_key =
      equals != std::string::npos && dot != std::string::npos && dot > 0 && dot + 1 < equals;
  const std::string section = has_section_and_key ? assignment.substr(0, dot) : "";
  const std::string key = has_section_and_key ? assignment.substr(dot + 1, equals - dot - 1) : "";
  if (!has_section_and_key || key.find_first_of(".:#{}[], ") != std::string::npos ||
      section.find_first_of(":#{}[], ") != std::string::npos) {
    *why = "'" + assignment + "': expected section.key=value (occupancy.resolution_m=0.02)";
    return false;
  }
  const std::string value = assignment.substr(equals + 1);
  // The same reader as a file's, so the same keys, types and messages: a one-key document.
  YAML::Node value_node;
  try {
    value_node = value.empty() ? YAML::Node(std::string()) : YAML::Load(value);
  } catch (const YAML::Exception& e) {
    *why = section + "." + key + ": cannot read the value '" + value + "': " + e.what();
    return false;
  }
  YAML::Node document;
  document[section][key] = value_node;
  YAML::Emitter text;
  text << document;
  return ParseObjmapConfig(text.c_str(), config, why);
}

bool ReadObjmapConfig(const std::string& path, const std::vector<std::string>& assignments,
                      ObjmapConfig* config, std::string* why) {
  if (!path.empty() && !LoadObjmapConfig(path, config, why)) return false;
  for (const std::string& assignment : assignments) {
    if (!SetObjmapConfigKey(assignment, config, why)) {
      *why = "--set " + *why;
      return false;
    }
  }
  return true;
}

std::string ObjmapConfigToYaml(const ObjmapConfig& config) {
  ObjmapConfig copy = config;
  Writer writer;
  internal::VisitObjmapConfig(&copy, writer);
  return writer.Text();
}

}  // namespace objmap
