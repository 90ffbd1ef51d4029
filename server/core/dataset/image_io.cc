#include "dataset/image_io.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

namespace objmap {

bool ReadColorImage(const std::string& path, ColorImage* image, std::string* why) {
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) {
    *why = path + ": missing or not a readable image";
    return false;
  }
  image->width = bgr.cols;
  image->height = bgr.rows;
  image->rgb.resize(static_cast<size_t>(bgr.cols) * bgr.rows * 3);
  for (int v = 0; v < bgr.rows; ++v) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    std::uint8_t* out = &image->rgb[static_cast<size_t>(v) * bgr.cols * 3];
    for (int u = 0; u < bgr.cols; ++u) {
      out[3 * u + 0] = row[u][2];
      out[3 * u + 1] = row[u][1];
      out[3 * u + 2] = row[u][0];
    }
  }
  return true;
}

bool ReadDepthImage(const std::string& path, double depth_units_per_metre, DepthImage* image,
                    std::string* why) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH);
  if (raw.empty()) {
    *why = path + ": missing or not a readable image";
    return false;
  }
  if (raw.type() != CV_16UC1) {
    *why = path + ": depth must be a single-channel 16-bit PNG";
    return false;
  }
  image->width = raw.cols;
  image->height = raw.rows;
  image->depth_m.resize(static_cast<size_t>(raw.cols) * raw.rows);
  const float scale = static_cast<float>(1.0 / depth_units_per_metre);
  for (int v = 0; v < raw.rows; ++v) {
    const std::uint16_t* row = raw.ptr<std::uint16_t>(v);
    float* out = &image->depth_m[static_cast<size_t>(v) * raw.cols];
    for (int u = 0; u < raw.cols; ++u) {
      // 7-Scenes marks invalid depth with 0 or 65535.
      out[u] = (row[u] == 0 || row[u] == 65535) ? 0.f : row[u] * scale;
    }
  }
  return true;
}

bool ReadMatrixText(const std::string& path, int rows, int cols, double* values, std::string* why) {
  std::ifstream in(path);
  if (!in) {
    *why = path + ": missing or unreadable";
    return false;
  }
  // Tokens go through strtod so that "nan" and "inf" are read (and rejected later by name).
  std::string token;
  for (int i = 0; i < rows * cols; ++i) {
    char* end = nullptr;
    if (!(in >> token) || (values[i] = std::strtod(token.c_str(), &end), *end != '\0')) {
      std::ostringstream text;
      text << path << ": expected " << rows << "x" << cols << " numbers, read " << i;
      *why = text.str();
      return false;
    }
  }
  return true;
}

}  // namespace objmap
