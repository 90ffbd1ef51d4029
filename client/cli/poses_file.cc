#include "poses_file.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "arguments.h"

namespace objmap::cli {
namespace {

// Text files round quaternions; farther than this from unit length is a wrong column, not noise.
constexpr double kMaxQuaternionNormError = 0.01;

std::vector<std::string> Words(const std::string& line) {
  std::istringstream stream(line.substr(0, line.find('#')));
  std::vector<std::string> words;
  for (std::string word; stream >> word;) words.push_back(word);
  return words;
}

// Parses the 8 fields of one line; false with a reason that the caller prefixes with the line.
bool ParsePoseWords(const std::vector<std::string>& words, KeyframePoseLine* pose,
                    std::string* why) {
  static const char* kNames[] = {"keyframe_id", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  if (words.size() != 8) {
    *why =
        "expected 8 fields (keyframe_id tx ty tz qx qy qz qw), got " + std::to_string(words.size());
    return false;
  }
  std::int64_t id = 0;
  if (!ParseInteger(words[0], &id) || id < 0) {
    *why = "keyframe_id must be a whole number >= 0, got '" + words[0] + "'";
    return false;
  }
  double values[7];
  for (int k = 0; k < 7; ++k) {
    if (!ParseNumber(words[k + 1], &values[k])) {
      *why = std::string(kNames[k + 1]) + " must be a finite number, got '" + words[k + 1] + "'";
      return false;
    }
  }
  Eigen::Quaterniond q(values[6], values[3], values[4], values[5]);
  if (std::abs(q.norm() - 1.0) > kMaxQuaternionNormError) {
    std::ostringstream text;
    text << "quaternion (qx qy qz qw) has norm " << q.norm() << ", not 1";
    *why = text.str();
    return false;
  }
  pose->keyframe_id = id;
  pose->T_W_C.setIdentity();
  pose->T_W_C.linear() = q.normalized().toRotationMatrix();
  pose->T_W_C.translation() = Eigen::Vector3d(values[0], values[1], values[2]);
  return true;
}

}  // namespace

bool ParsePosesText(const std::string& text, std::vector<KeyframePoseLine>* poses,
                    std::string* why) {
  std::istringstream stream(text);
  std::map<KeyframeId, int> line_of_keyframe;
  int line_number = 0;
  for (std::string line; std::getline(stream, line);) {
    ++line_number;
    const std::vector<std::string> words = Words(line);
    if (words.empty()) continue;
    KeyframePoseLine pose;
    std::string reason;
    if (!ParsePoseWords(words, &pose, &reason)) {
      *why = "line " + std::to_string(line_number) + ": " + reason;
      return false;
    }
    pose.line = line_number;
    const auto [it, inserted] = line_of_keyframe.emplace(pose.keyframe_id, line_number);
    if (!inserted) {
      *why = "line " + std::to_string(line_number) + ": keyframe " +
             std::to_string(pose.keyframe_id) + " was already given on line " +
             std::to_string(it->second);
      return false;
    }
    poses->push_back(pose);
  }
  if (poses->empty()) {
    *why = "no poses (expected lines \"keyframe_id tx ty tz qx qy qz qw\")";
    return false;
  }
  return true;
}

bool ReadPosesFile(const std::string& path, std::vector<KeyframePoseLine>* poses,
                   std::string* why) {
  std::ifstream file(path);
  if (!file) {
    *why = path + ": cannot be opened";
    return false;
  }
  std::ostringstream text;
  text << file.rdbuf();
  if (!ParsePosesText(text.str(), poses, why)) {
    *why = path + ": " + *why;
    return false;
  }
  return true;
}

std::string FormatPoseLine(KeyframeId keyframe_id, const Eigen::Vector3d& t,
                           const Eigen::Quaterniond& q, const std::string& comment) {
  char line[256];
  std::snprintf(line, sizeof(line), "%lld %.9g %.9g %.9g %.9g %.9g %.9g %.9g",
                static_cast<long long>(keyframe_id), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                q.w());
  return std::string(line) + (comment.empty() ? "" : "  # " + comment) + "\n";
}

}  // namespace objmap::cli
