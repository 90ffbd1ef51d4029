#include "map_run_outputs.h"

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace objmap::cli {

bool RecordingDetector::Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
                               std::string* why) {
  if (!inner_->Detect(frame, detections, why)) return false;
  recorded_[frame.name] = *detections;
  // The detector sees every keyframe's colour image, and only those: kept as JPEG (about
  // 50 kB each) for the map folder's keyframes/, which the viewer crops detections from.
  if (!frame.color.empty()) {
    const cv::Mat rgb(frame.color.height, frame.color.width, CV_8UC3,
                      const_cast<std::uint8_t*>(frame.color.rgb.data()));
    cv::Mat bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    std::vector<std::uint8_t>& jpeg = keyframe_jpegs_[frame.frame_index];
    if (!cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 85})) {
      keyframe_jpegs_.erase(frame.frame_index);
    }
  }
  return true;
}

// keyframes/<keyframe id>.jpg: the colour image of each mapped keyframe.
bool WriteKeyframeImages(const SequenceRunReport& report,
                         const std::map<std::int64_t, std::vector<std::uint8_t>>& jpegs,
                         const std::string& dir, std::string* why) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  for (const KeyframeReport& keyframe : report.keyframes) {
    const auto it = jpegs.find(static_cast<std::int64_t>(keyframe.frame_index));
    // Keyframe id 0: kept as a revisit of a stored view, not a keyframe of the map.
    if (it == jpegs.end() || keyframe.result.keyframe_id == 0) continue;
    const std::string path = dir + "/" + std::to_string(keyframe.result.keyframe_id) + ".jpg";
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(it->second.data()),
              static_cast<std::streamsize>(it->second.size()));
    if (!out) {
      *why = path + ": write failed";
      return false;
    }
  }
  return true;
}

bool WriteTimings(const SequenceRunReport& report, const std::string& path, std::string* why) {
  std::ofstream out(path);
  out << "frame,detection_ms,segmentation_ms,association_ms,occupancy_ms,detections,used\n";
  for (const KeyframeReport& k : report.keyframes) {
    out << k.frame_index << "," << k.detection_ms << "," << k.result.timings.segmentation_ms << ","
        << k.result.timings.association_ms << "," << k.result.timings.occupancy_ms << ","
        << k.detections << "," << k.result.detections_used << "\n";
  }
  if (!out) *why = path + ": write failed";
  return static_cast<bool>(out);
}

}  // namespace objmap::cli
