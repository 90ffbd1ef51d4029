#include "player_config.h"

#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <type_traits>
#include <vector>

#include "ros_params.h"

namespace objmap::ros_player {
namespace {

template <typename Visitor>
void VisitPlayerKeys(PlayerConfig* c, Visitor& v) {
  v("dataset", &c->dataset);
  v("rate", &c->rate_hz);
  v("first_frame", &c->first_frame);
  v("max_frames", &c->max_frames);
  v("every_nth_frame", &c->every_nth_frame);
  v("loop", &c->loop);
  v("world_frame", &c->world_frame);
  v("camera_frame", &c->camera_frame);
  v("wait_for_node", &c->wait_for_node);
  v("wait_timeout_s", &c->wait_timeout_s);
  v("write_bag", &c->write_bag);
}

// The command-line twin of ros_bridge::RosParamReader: key "first_frame" is option
// --first-frame; a lone word is the dataset. Stops at the first problem.
class CommandLineReader {
 public:
  CommandLineReader(int argc, char** argv) {
    for (int i = 1; i < argc; ++i) {
      const std::string word = argv[i];
      if (word.rfind("--", 0) != 0) {
        positional_.push_back(word);
      } else if (i + 1 >= argc) {
        error_ = word + " needs a value";
      } else {
        values_[word] = argv[++i];
      }
    }
  }

  template <typename T>
  void operator()(const char* key, T* value) {
    std::string flag = std::string("--") + key;
    for (char& c : flag) c = c == '_' ? '-' : c;
    known_.insert(flag);
    const auto found = values_.find(flag);
    if (!error_.empty() || found == values_.end()) return;
    if (!Convert(found->second, value)) {
      error_ =
          flag + ": expected " + ros_bridge::ExpectedValue<T>() + ", got '" + found->second + "'";
    }
  }

  // After the keys: no unknown option, at most one lone word (the dataset).
  void Finish(std::string* dataset) {
    for (const auto& [flag, value] : values_) {
      if (error_.empty() && known_.count(flag) == 0) error_ = flag + ": unknown option";
    }
    if (!error_.empty()) return;
    if (positional_.size() > 1) error_ = "one dataset folder expected, got several";
    if (positional_.size() == 1) *dataset = positional_.front();
  }

  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  template <typename T>
  static bool Convert(const std::string& text, T* out) {
    char* end = nullptr;
    if constexpr (std::is_same_v<T, bool>) {
      if (text != "true" && text != "false") return false;
      *out = text == "true";
    } else if constexpr (std::is_integral_v<T>) {
      const long value = std::strtol(text.c_str(), &end, 10);
      if (text.empty() || *end != '\0') return false;
      *out = static_cast<T>(value);
    } else if constexpr (std::is_floating_point_v<T>) {
      const double value = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0' || !std::isfinite(value)) return false;
      *out = static_cast<T>(value);
    } else {
      *out = text;
    }
    return true;
  }

  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::set<std::string> known_;
  std::string error_;
};

}  // namespace

const char kPlayerUsage[] =
    "usage: objmap_dataset_player DATASET --write-bag FILE.bag [options]   (no rosmaster)\n"
    "       rosrun objmap objmap_dataset_player _dataset:=DATASET [_param:=value ...]\n"
    "  DATASET                7-Scenes or TUM RGB-D folder\n"
    "  --write-bag FILE       write /rgb/image, /depth/image, /rgb/camera_info, /tf to a bag\n"
    "  --rate HZ              frames per second, stamp spacing without dataset stamps (10)\n"
    "  --first-frame N        first frame index (0)\n"
    "  --max-frames N         frames from the first one, 0: all (0)\n"
    "  --every-nth-frame N    every n-th frame (1)\n"
    "  --world-frame F        TF parent frame (map)\n"
    "  --camera-frame F       image frame_id and TF child frame (camera_rgb_optical_frame)\n"
    "ROS parameters have the same names with underscores (~first_frame), plus ~loop,\n"
    "~wait_for_node (a Status service, e.g. /objmap_node/status) and ~wait_timeout_s.\n";

bool PlayerConfig::IsValid(std::string* why) const {
  if (dataset.empty()) {
    *why = "dataset: no dataset folder given";
    return false;
  }
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    *why = "rate: must be positive (frames per second)";
    return false;
  }
  if (first_frame < 0 || max_frames < 0 || every_nth_frame < 1) {
    *why = "first_frame and max_frames must be >= 0, every_nth_frame >= 1";
    return false;
  }
  if (world_frame.empty() || camera_frame.empty()) {
    *why = "world_frame and camera_frame must not be empty";
    return false;
  }
  if (!(wait_timeout_s > 0.0)) {
    *why = "wait_timeout_s must be positive";
    return false;
  }
  if (!write_bag.empty() && (loop || !wait_for_node.empty())) {
    *why = "write_bag: a bag is written once and without a node; unset loop and wait_for_node";
    return false;
  }
  return true;
}

bool LoadPlayerConfig(const ros::NodeHandle& private_node, PlayerConfig* config, std::string* why) {
  ros_bridge::RosParamReader reader(
      private_node,
      "objmap_dataset_player's parameters are listed in server/ros_player/"
      "player_config.h and launch/objmap_dataset.launch");
  VisitPlayerKeys(config, reader);
  reader.Finish();
  if (!reader.ok()) {
    *why = reader.error();
    return false;
  }
  if (!config->IsValid(why)) {
    *why = "~" + *why;
    return false;
  }
  return true;
}

bool ParsePlayerCommandLine(int argc, char** argv, PlayerConfig* config, std::string* why) {
  CommandLineReader reader(argc, argv);
  VisitPlayerKeys(config, reader);
  reader.Finish(&config->dataset);
  if (!reader.error().empty()) {
    *why = reader.error();
    return false;
  }
  return config->IsValid(why);
}

}  // namespace objmap::ros_player
