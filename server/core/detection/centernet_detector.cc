#include "detection/centernet_detector.h"

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "detection/centernet_decode.h"
#include "detection/tiling.h"
#include "types/coco_classes.h"

namespace objmap {
namespace {

// Output tensors of the converted graph (scripts/convert_centernet.py).
constexpr const char* kHeatmapOutput = "tower_0/Sigmoid";
constexpr const char* kBoxOutput = "tower_0/mul";
constexpr int kBoxChannels = 4;

void SetWhy(std::string* why, const std::string& text) {
  if (why != nullptr) *why = text;
}

std::string FrameLabel(const RgbdFrame& frame) {
  return frame.name.empty() ? "frame " + std::to_string(frame.frame_index) : frame.name;
}

/// True when `m` is a 1 x channels x H x W blob.
bool HasShape(const cv::Mat& m, int channels) {
  return m.dims == 4 && m.size[0] == 1 && m.size[1] == channels && m.type() == CV_32F &&
         m.isContinuous();
}

// Decoding of a network pass over a `width` x `height` region of the image.
CenterNetDecodeParams MakeDecodeParams(const CenterNetConfig& config, int width, int height,
                                       const cv::Mat& heatmap) {
  const float input_px = static_cast<float>(config.input_size);
  CenterNetDecodeParams params;
  params.num_classes = kNumCocoClasses;
  params.grid_height = heatmap.size[2];
  params.grid_width = heatmap.size[3];
  params.stride_px = input_px / static_cast<float>(params.grid_width);
  params.scale_x = static_cast<float>(width) / input_px;
  params.scale_y = static_cast<float>(height) / input_px;
  params.image_width = static_cast<float>(width);
  params.image_height = static_cast<float>(height);
  params.score_threshold = config.score_threshold;
  params.max_detections = config.max_detections;
  params.nms_iou = config.nms_iou;
  return params;
}

/// Not thread-safe: cv::dnn::Net keeps per-forward state, so use one instance per thread.
class CenterNetDetector final : public Detector {
 public:
  CenterNetDetector(CenterNetConfig config, cv::dnn::Net net)
      : config_(std::move(config)), net_(std::move(net)) {}

  bool Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
              std::string* why) override;
  std::string Name() const override { return "centernet"; }

 private:
  // One network pass over `region` of `rgb`; boxes in the pixels of `rgb`.
  bool DetectIn(const cv::Mat& rgb, const cv::Rect& region, const RgbdFrame& frame,
                std::vector<Detection>* detections, std::string* why);

  CenterNetConfig config_;
  cv::dnn::Net net_;
  std::vector<cv::Mat> outputs_;  // reused between frames to avoid reallocation
};

bool CenterNetDetector::DetectIn(const cv::Mat& rgb, const cv::Rect& region, const RgbdFrame& frame,
                                 std::vector<Detection>* detections, std::string* why) {
  // The network takes RGB 0-255 without normalisation; a plain (non letter-boxed) resize is what
  // the TF.js model was run with.
  cv::Mat resized;
  cv::resize(rgb(region), resized, cv::Size(config_.input_size, config_.input_size), 0, 0,
             cv::INTER_LINEAR);
  net_.setInput(
      cv::dnn::blobFromImage(resized, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F));
  try {
    net_.forward(outputs_, std::vector<cv::String>{kHeatmapOutput, kBoxOutput});
  } catch (const cv::Exception& e) {
    SetWhy(why, FrameLabel(frame) + ": network forward failed: " + e.what());
    return false;
  }
  const cv::Mat& heatmap = outputs_[0];
  const cv::Mat& boxes = outputs_[1];
  if (!HasShape(heatmap, kNumCocoClasses) || !HasShape(boxes, kBoxChannels) ||
      heatmap.size[2] != boxes.size[2] || heatmap.size[3] != boxes.size[3]) {
    SetWhy(why, FrameLabel(frame) + ": network outputs have unexpected shapes");
    return false;
  }
  const CenterNetDecodeParams params =
      MakeDecodeParams(config_, region.width, region.height, heatmap);
  *detections = DecodeCenterNet(heatmap.ptr<float>(), boxes.ptr<float>(), params);
  for (Detection& detection : *detections) {
    detection.box.x_min += static_cast<float>(region.x);
    detection.box.x_max += static_cast<float>(region.x);
    detection.box.y_min += static_cast<float>(region.y);
    detection.box.y_max += static_cast<float>(region.y);
  }
  return true;
}

bool CenterNetDetector::Detect(const RgbdFrame& frame, std::vector<Detection>* detections,
                               std::string* why) {
  detections->clear();
  const ColorImage& image = frame.color;
  if (image.empty() || image.rgb.size() != static_cast<std::size_t>(image.width) *
                                               static_cast<std::size_t>(image.height) * 3) {
    SetWhy(why, FrameLabel(frame) + ": colour image is empty or its size does not match");
    return false;
  }
  // Read-only view of the caller's pixels; resize writes into its own buffer.
  const cv::Mat rgb(image.height, image.width, CV_8UC3,
                    const_cast<std::uint8_t*>(image.rgb.data()));
  std::vector<Detection> whole_image;
  if (!DetectIn(rgb, cv::Rect(0, 0, image.width, image.height), frame, &whole_image, why)) {
    return false;
  }
  const std::vector<ImageTile> grid =
      TileGrid(image.width, image.height, config_.tiles_per_side, config_.tile_overlap);
  if (grid.empty()) {
    *detections = std::move(whole_image);
    return true;
  }
  std::vector<TileDetections> tiles;
  tiles.reserve(grid.size());
  for (const ImageTile& tile : grid) {
    TileDetections& in_tile = tiles.emplace_back();
    in_tile.tile = tile;
    if (!DetectIn(rgb, cv::Rect(tile.x, tile.y, tile.width, tile.height), frame,
                  &in_tile.detections, why)) {
      return false;
    }
  }
  TileMergeParams merge;
  merge.image_width = image.width;
  merge.image_height = image.height;
  merge.nms_iou = config_.nms_iou;
  merge.max_detections = config_.max_detections;
  *detections = MergeTileDetections(std::move(whole_image), tiles, merge);
  return true;
}

}  // namespace

bool CenterNetConfig::IsValid(std::string* why) const {
  if (model_path.empty()) {
    SetWhy(why, "centernet: model_path is empty");
    return false;
  }
  if (!(score_threshold >= 0.f && score_threshold <= 1.f)) {
    SetWhy(why, "centernet: score_threshold must lie in [0, 1]");
    return false;
  }
  // The backbone downsamples by 32, so other sizes would not line up with the head.
  if (input_size < 32 || input_size % 32 != 0) {
    SetWhy(why, "centernet: input_size must be a positive multiple of 32");
    return false;
  }
  if (max_detections <= 0) {
    SetWhy(why, "centernet: max_detections must be positive");
    return false;
  }
  if (num_threads < 0) {
    SetWhy(why, "centernet: num_threads must be >= 0");
    return false;
  }
  if (!(nms_iou > 0.f && nms_iou <= 1.f)) {
    SetWhy(why, "centernet: nms_iou must lie in (0, 1]");
    return false;
  }
  if (tiles_per_side < 1 || tiles_per_side > 4) {
    SetWhy(why, "centernet: tiles_per_side must lie in [1, 4]");
    return false;
  }
  if (!(tile_overlap >= 0.f && tile_overlap < 0.9f)) {
    SetWhy(why, "centernet: tile_overlap must lie in [0, 0.9)");
    return false;
  }
  return true;
}

std::unique_ptr<Detector> MakeCenterNetDetector(const CenterNetConfig& config, std::string* why) {
  if (!config.IsValid(why)) return nullptr;
  std::error_code error;
  if (!std::filesystem::is_regular_file(config.model_path, error)) {
    SetWhy(why, "centernet: model file " + config.model_path +
                    " not found (run scripts/fetch_model.sh)");
    return nullptr;
  }
  cv::dnn::Net net;
  try {
    net = cv::dnn::readNetFromTensorflow(config.model_path);
  } catch (const cv::Exception& e) {
    SetWhy(why, "centernet: cannot load " + config.model_path + ": " + e.what());
    return nullptr;
  }
  if (net.empty()) {
    SetWhy(why, "centernet: " + config.model_path + " holds no network");
    return nullptr;
  }
  net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  if (config.num_threads > 0) cv::setNumThreads(config.num_threads);
  auto detector = std::make_unique<CenterNetDetector>(config, std::move(net));
  // One pass on a blank image now: a graph converted for another input size (its upsampling
  // sizes are fixed) would otherwise fail on every frame, each skipped with the same reason.
  RgbdFrame trial;
  trial.name = "a blank " + std::to_string(config.input_size) + " px test image";
  trial.color.width = trial.color.height = config.input_size;
  trial.color.rgb.assign(static_cast<std::size_t>(config.input_size) * config.input_size * 3, 0);
  std::vector<Detection> none;
  std::string failure;
  if (!detector->Detect(trial, &none, &failure)) {
    SetWhy(why, "centernet: " + config.model_path + " does not run at input_size " +
                    std::to_string(config.input_size) +
                    " (a converted graph keeps the size it was converted for; "
                    "scripts/convert_centernet.py makes 512): " + failure);
    return nullptr;
  }
  return detector;
}

}  // namespace objmap
