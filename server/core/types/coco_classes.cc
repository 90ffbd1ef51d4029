#include "types/coco_classes.h"

#include <array>

namespace objmap {
namespace {

constexpr std::array<std::string_view, kNumCocoClasses> kCocoNames = {
    "person",        "bicycle",      "car",
    "motorcycle",    "airplane",     "bus",
    "train",         "truck",        "boat",
    "traffic light", "fire hydrant", "stop sign",
    "parking meter", "bench",        "bird",
    "cat",           "dog",          "horse",
    "sheep",         "cow",          "elephant",
    "bear",          "zebra",        "giraffe",
    "backpack",      "umbrella",     "handbag",
    "tie",           "suitcase",     "frisbee",
    "skis",          "snowboard",    "sports ball",
    "kite",          "baseball bat", "baseball glove",
    "skateboard",    "surfboard",    "tennis racket",
    "bottle",        "wine glass",   "cup",
    "fork",          "knife",        "spoon",
    "bowl",          "banana",       "apple",
    "sandwich",      "orange",       "broccoli",
    "carrot",        "hot dog",      "pizza",
    "donut",         "cake",         "chair",
    "couch",         "potted plant", "bed",
    "dining table",  "toilet",       "tv",
    "laptop",        "mouse",        "remote",
    "keyboard",      "cell phone",   "microwave",
    "oven",          "toaster",      "sink",
    "refrigerator",  "book",         "clock",
    "vase",          "scissors",     "teddy bear",
    "hair drier",    "toothbrush"};

}  // namespace

std::string_view CocoClassName(int class_id) {
  if (class_id < 0 || class_id >= kNumCocoClasses) return {};
  return kCocoNames[class_id];
}

int CocoClassId(std::string_view name) {
  std::string normalized(name);
  for (char& c : normalized) {
    if (c == '_') c = ' ';
  }
  for (int i = 0; i < kNumCocoClasses; ++i) {
    if (kCocoNames[i] == normalized) return i;
  }
  return -1;
}

std::string_view ObjectClassName(int class_id) {
  if (class_id == kUnknownClassId) return "unknown";
  return CocoClassName(class_id);
}

int ObjectClassId(std::string_view name) {
  if (name == "unknown") return kUnknownClassId;
  return CocoClassId(name);
}

std::string CocoClassFileName(int class_id) {
  std::string name(CocoClassName(class_id));
  for (char& c : name) {
    if (c == ' ') c = '_';
  }
  return name.empty() ? "unknown" : name;
}

std::string ObjectModelFileName(std::int64_t object_id, int class_id) {
  return std::to_string(object_id) + "_" + CocoClassFileName(class_id) + ".ply";
}

}  // namespace objmap
