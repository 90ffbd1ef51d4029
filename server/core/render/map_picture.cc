#include "render/map_picture.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "types/coco_classes.h"

namespace objmap {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kNearM = 0.05f;
constexpr RgbColour kBackground = {255, 255, 255};
constexpr RgbColour kUnknownColour = {150, 110, 200};
// A qualitative palette of saturated colours (none of them grey), indexed by COCO class id.
constexpr std::array<RgbColour, 20> kPalette = {{
    {31, 119, 180},  {255, 127, 14}, {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
    {140, 86, 75},   {227, 119, 194}, {23, 190, 207}, {188, 189, 34}, {0, 90, 200},
    {230, 60, 0},    {0, 150, 110},  {200, 0, 90},    {120, 60, 220}, {255, 190, 0},
    {0, 170, 255},   {170, 40, 140}, {90, 170, 0},    {255, 80, 120}, {0, 110, 140},
}};

// The points of one kind drawn into the depth and colour buffers.
struct Raster {
  int width = 0, height = 0;
  std::vector<float> depth;  // camera z, +inf where nothing was drawn
  std::vector<RgbColour> colour;
};

struct Frame {
  PictureCamera camera;
  Eigen::Vector3d focus_W = Eigen::Vector3d::Zero();  // what the view centres on
};

double Radians(double degrees) { return degrees * kPi / 180.0; }

// Two horizontal axes (perpendicular to up): h1 along the content's longest horizontal spread,
// so that a top view fills the wide side of the picture with it.
void HorizontalAxes(const std::vector<Eigen::Vector3d>& sample, const Eigen::Vector3d& up,
                    Eigen::Vector3d* h1, Eigen::Vector3d* h2) {
  Eigen::Vector3d seed = std::abs(up.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Vector3d a = (seed - up * up.dot(seed)).normalized();
  Eigen::Vector3d b = up.cross(a);
  if (sample.size() >= 3) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : sample) mean += Eigen::Vector2d(p.dot(a), p.dot(b));
    mean /= static_cast<double>(sample.size());
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
    for (const auto& p : sample) {
      const Eigen::Vector2d d = Eigen::Vector2d(p.dot(a), p.dot(b)) - mean;
      covariance += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
    const Eigen::Vector2d major = eigen.eigenvectors().col(1);
    if (major.allFinite() && major.norm() > 0.5) {
      const Eigen::Vector3d along = (major.x() * a + major.y() * b).normalized();
      a = along;
      b = up.cross(a);
    }
  }
  *h1 = a;
  *h2 = b;
}

PictureCamera Pinhole(const PictureConfig& config, double fov_deg, const Eigen::Matrix3d& R_W_C,
                      const Eigen::Vector3d& position_W) {
  PictureCamera camera;
  camera.T_W_C.linear() = R_W_C;
  camera.T_W_C.translation() = position_W;
  camera.fy = 0.5 * config.height / std::tan(0.5 * Radians(fov_deg));
  camera.fx = camera.fy;
  camera.cx = 0.5 * config.width;
  camera.cy = 0.5 * config.height;
  return camera;
}

// Moves the camera back along its axis until every sample point lies inside the picture with a
// margin, then sideways so that the content is centred.
void FitCamera(const std::vector<Eigen::Vector3d>& sample, PictureCamera* camera,
               Eigen::Vector3d* focus_W) {
  if (sample.empty()) return;
  constexpr double kFill = 0.9;
  const Eigen::Matrix3d R = camera->T_W_C.linear();
  const double tan_x = kFill * camera->cx / camera->fx, tan_y = kFill * camera->cy / camera->fy;
  // Camera at focus - d * forward: a point q (camera axes, from the focus) has depth q.z + d.
  double distance = 0.1;
  for (const Eigen::Vector3d& p : sample) {
    const Eigen::Vector3d q = R.transpose() * (p - *focus_W);
    distance = std::max({distance, std::abs(q.x()) / tan_x - q.z(), std::abs(q.y()) / tan_y - q.z()});
  }
  // Centre the content: shift the focus by the middle of its projected extent.
  double u_min = 1e9, u_max = -1e9, v_min = 1e9, v_max = -1e9;
  for (const Eigen::Vector3d& p : sample) {
    const Eigen::Vector3d q = R.transpose() * (p - *focus_W);
    const double z = q.z() + distance;
    if (z <= 1e-6) continue;
    u_min = std::min(u_min, q.x() / z);
    u_max = std::max(u_max, q.x() / z);
    v_min = std::min(v_min, q.y() / z);
    v_max = std::max(v_max, q.y() / z);
  }
  if (u_min <= u_max) {
    *focus_W += R * Eigen::Vector3d(0.5 * (u_min + u_max) * distance, 0.5 * (v_min + v_max) * distance, 0.0);
  }
  camera->T_W_C.translation() = *focus_W - distance * R.col(2);
}

// Where the camera goes to frame `bounds` (the content to show) for the configured view.
Frame FrameView(const Eigen::AlignedBox3d& bounds, const std::vector<Eigen::Vector3d>& sample,
                const PictureConfig& config) {
  Frame frame;
  const Eigen::Vector3d up = config.up_W.normalized();
  frame.focus_W = bounds.center();
  if (config.view == PictureView::kCamera) {
    frame.camera = Pinhole(config, config.fov_deg, config.T_W_C.linear(), config.T_W_C.translation());
    // The focus is where the optical axis passes the content's centre.
    const Eigen::Vector3d forward = config.T_W_C.linear().col(2);
    const double along = std::max(0.5, (frame.focus_W - config.T_W_C.translation()).dot(forward));
    frame.focus_W = config.T_W_C.translation() + along * forward;
    return frame;
  }
  Eigen::Vector3d h1, h2;
  HorizontalAxes(sample, up, &h1, &h2);
  // The region's corners frame a region view even where the map leaves it empty.
  std::vector<Eigen::Vector3d> fitted = sample;
  if (config.region) {
    for (int corner = 0; corner < 8; ++corner) {
      fitted.push_back(bounds.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)));
    }
  }
  Eigen::Matrix3d R;
  double fov_deg = config.fov_deg;
  if (config.view == PictureView::kTop) {
    R.col(0) = h1;   // image right: the content's long side
    R.col(2) = -up;  // looking down
    R.col(1) = R.col(2).cross(R.col(0));
    fov_deg = config.top_fov_deg;
  } else {
    // Perspective: from 35 degrees above the horizon, beside the long side, turned 30 degrees.
    const double elevation = Radians(35.0), azimuth = Radians(-60.0);
    const Eigen::Vector3d offset =
        std::cos(elevation) * (std::cos(azimuth) * h1 + std::sin(azimuth) * h2) +
        std::sin(elevation) * up;
    R.col(2) = -offset.normalized();
    R.col(0) = R.col(2).cross(up).normalized();
    R.col(1) = R.col(2).cross(R.col(0));
  }
  frame.camera = Pinhole(config, fov_deg, R, frame.focus_W);
  FitCamera(fitted, &frame.camera, &frame.focus_W);
  return frame;
}

// Draws each point as a square of its voxel's projected size, nearest first wins; `bias_m`
// draws them as if that much nearer, so that a book lying on a table is not lost in it.
void Splat(const std::vector<Eigen::Vector3f>& points, float voxel_m, const PictureCamera& camera,
           const std::function<RgbColour(const Eigen::Vector3f&)>& colour_of,
           const std::optional<Eigen::AlignedBox3f>& region, float bias_m, Raster* raster) {
  const Eigen::Isometry3f T_C_W = camera.T_W_C.inverse().cast<float>();
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  for (const Eigen::Vector3f& p_W : points) {
    if (region && !region->contains(p_W)) continue;
    const Eigen::Vector3f p = T_C_W * p_W;
    if (!(p.z() > kNearM)) continue;
    const float u = fx * p.x() / p.z() + cx, v = fy * p.y() / p.z() + cy;
    const float half = std::min(40.f, std::max(0.5f, 0.5f * voxel_m * fx / p.z()));
    const int u0 = std::max(0, static_cast<int>(std::floor(u - half)));
    const int u1 = std::min(raster->width - 1, static_cast<int>(std::ceil(u + half)) - 1);
    const int v0 = std::max(0, static_cast<int>(std::floor(v - half)));
    const int v1 = std::min(raster->height - 1, static_cast<int>(std::ceil(v + half)) - 1);
    if (u0 > u1 || v0 > v1) continue;
    const RgbColour colour = colour_of(p_W);
    for (int y = v0; y <= v1; ++y) {
      for (int x = u0; x <= u1; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * raster->width + x;
        if (p.z() - bias_m < raster->depth[i]) {
          raster->depth[i] = p.z() - bias_m;
          raster->colour[i] = colour;
        }
      }
    }
  }
}

// Eye-dome lighting: a pixel nearer the camera than its neighbours keeps its colour, one
// behind them (a crease, the far side of an edge) darkens. Gives shape to points without
// normals; flat faces seen head-on are unchanged.
void EyeDomeShade(const Raster& raster, std::vector<std::uint8_t>* rgb) {
  constexpr int kReach = 2;
  constexpr float kStrength = 12.f;
  constexpr float kBackgroundStep = 0.08f;  // an outline where the points end
  for (int y = 0; y < raster.height; ++y) {
    for (int x = 0; x < raster.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * raster.width + x;
      const float z = raster.depth[i];
      RgbColour colour = kBackground;
      if (std::isfinite(z)) {
        const float log_z = std::log(z);
        float response = 0.f;
        const int offsets[4][2] = {{kReach, 0}, {-kReach, 0}, {0, kReach}, {0, -kReach}};
        for (const auto& offset : offsets) {
          const int nx = x + offset[0], ny = y + offset[1];
          if (nx < 0 || ny < 0 || nx >= raster.width || ny >= raster.height) continue;
          const float zn = raster.depth[static_cast<std::size_t>(ny) * raster.width + nx];
          response += std::isfinite(zn) ? std::max(0.f, log_z - std::log(zn)) : kBackgroundStep;
        }
        const float shade = std::exp(-kStrength * response);
        colour = raster.colour[i];
        for (auto& channel : colour) {
          channel = static_cast<std::uint8_t>(std::lround(channel * (0.25f + 0.75f * shade)));
        }
      }
      std::copy(colour.begin(), colour.end(), rgb->begin() + static_cast<std::ptrdiff_t>(3 * i));
    }
  }
}

cv::Scalar Scalar(const RgbColour& c) { return cv::Scalar(c[0], c[1], c[2]); }

// A label box above the object, moved up (then down) until it overlaps no earlier one.
cv::Rect PlaceLabel(const cv::Size& size, const cv::Point& anchor, const cv::Size& image,
                    const std::vector<cv::Rect>& taken) {
  cv::Rect rect(anchor.x - size.width / 2, anchor.y - size.height, size.width, size.height);
  const auto clamp = [&](cv::Rect r) {
    r.x = std::clamp(r.x, 0, std::max(0, image.width - r.width));
    r.y = std::clamp(r.y, 0, std::max(0, image.height - r.height));
    return r;
  };
  const auto free = [&](const cv::Rect& r) {
    return std::none_of(taken.begin(), taken.end(),
                        [&](const cv::Rect& t) { return (r & t).area() > 0; });
  };
  for (int attempt = 0; attempt < 12; ++attempt) {
    for (const int direction : {-1, 1}) {
      cv::Rect moved = rect;
      moved.y += direction * attempt * (size.height + 2);
      moved = clamp(moved);
      if (free(moved)) return moved;
    }
  }
  return clamp(rect);
}

double NiceLength(double metres) {
  const double steps[] = {0.01, 0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1, 2, 5, 10, 20, 50, 100};
  double best = steps[0];
  for (const double step : steps) {
    if (step <= metres) best = step;
  }
  return best;
}

std::string LengthText(double metres) {
  char text[32];
  if (metres < 1.0) {
    std::snprintf(text, sizeof text, "%g cm", metres * 100.0);
  } else {
    std::snprintf(text, sizeof text, "%g m", metres);
  }
  return text;
}

}  // namespace

const char* PictureViewName(PictureView view) {
  switch (view) {
    case PictureView::kTop:
      return "top";
    case PictureView::kPerspective:
      return "perspective";
    case PictureView::kCamera:
      return "camera";
  }
  return "?";
}

bool ParsePictureView(const std::string& name, PictureView* view) {
  for (const PictureView candidate :
       {PictureView::kTop, PictureView::kPerspective, PictureView::kCamera}) {
    if (name == PictureViewName(candidate)) {
      *view = candidate;
      return true;
    }
  }
  return false;
}

bool PictureConfig::IsValid(std::string* why) const {
  if (width < 64 || height < 64 || width > 8192 || height > 8192) {
    *why = "the picture must be 64 to 8192 pixels wide and high, not " + std::to_string(width) +
           "x" + std::to_string(height);
    return false;
  }
  if (!(fov_deg > 5.0 && fov_deg < 150.0) || !(top_fov_deg > 5.0 && top_fov_deg < 150.0)) {
    *why = "the field of view must lie between 5 and 150 degrees";
    return false;
  }
  if (!up_W.allFinite() || up_W.norm() < 1e-6) {
    *why = "the up direction must be a finite, non-zero vector";
    return false;
  }
  if (!T_W_C.matrix().allFinite() ||
      !(T_W_C.linear().transpose() * T_W_C.linear()).isIdentity(1e-3)) {
    *why = "the camera pose must be a finite rigid transform";
    return false;
  }
  if (region && (region->isEmpty() || !region->min().allFinite() || !region->max().allFinite())) {
    *why = "the region must be a finite box with min <= max";
    return false;
  }
  return true;
}

std::optional<Eigen::Vector2d> PictureCamera::Project(const Eigen::Vector3d& point_W) const {
  const Eigen::Vector3d p = T_W_C.inverse() * point_W;
  if (!(p.z() > 0.0)) return std::nullopt;
  return Eigen::Vector2d(fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy);
}

RgbColour ClassColour(const std::string& class_name) {
  const int id = CocoClassId(class_name);
  if (id < 0) return kUnknownColour;
  return kPalette[static_cast<std::size_t>(id) % kPalette.size()];
}

bool RenderMapPicture(const PictureScene& scene, const PictureConfig& config, MapPicture* picture,
                      std::string* why) {
  if (!config.IsValid(why)) return false;
  if (!(scene.structure_voxel_m > 0.f) || !(scene.object_voxel_m > 0.f)) {
    *why = "voxel sizes must be positive";
    return false;
  }
  const auto inside = [&](const Eigen::Vector3f& p) { return !config.region || config.region->contains(p); };
  // Objects in colour: of the class asked for (or all), with a point in the region.
  std::vector<const PictureObject*> shown, others;
  for (const PictureObject& object : scene.objects) {
    const bool in_region = std::any_of(object.points_W.begin(), object.points_W.end(), inside);
    if (!in_region) continue;
    (config.only_class.empty() || object.class_name == config.only_class ? shown : others)
        .push_back(&object);
  }
  // What the view frames: the region, else the objects of the class, else everything.
  Eigen::AlignedBox3d bounds;
  std::vector<Eigen::Vector3d> sample;  // for the horizontal axes, at most ~20000 points
  const auto add = [&](const std::vector<Eigen::Vector3f>& points) {
    const std::size_t stride = std::max<std::size_t>(1, points.size() / 20000);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!inside(points[i])) continue;
      bounds.extend(points[i].cast<double>());
      if (i % stride == 0) sample.push_back(points[i].cast<double>());
    }
  };
  if (!config.only_class.empty()) {
    if (shown.empty()) {
      *why = "no object of class \"" + config.only_class + "\"" + (config.region ? " in the region" : "");
      return false;
    }
    for (const PictureObject* object : shown) add(object->points_W);
  } else {
    add(scene.structure_W);
    for (const PictureObject* object : shown) add(object->points_W);
  }
  if (bounds.isEmpty()) {
    *why = config.region ? "nothing of the map lies in the region" : "the map is empty";
    return false;
  }
  if (config.region && config.view != PictureView::kCamera) {
    bounds = config.region->cast<double>();
  }
  const Frame frame = FrameView(bounds, sample, config);

  Raster raster;
  raster.width = config.width;
  raster.height = config.height;
  const std::size_t pixels = static_cast<std::size_t>(config.width) * config.height;
  raster.depth.assign(pixels, std::numeric_limits<float>::infinity());
  raster.colour.assign(pixels, kBackground);
  // Structure grey by height: the lowest dark, the highest light.
  const Eigen::Vector3f up = config.up_W.normalized().cast<float>();
  float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
  for (const Eigen::Vector3f& p : scene.structure_W) {
    if (!inside(p)) continue;
    low = std::min(low, p.dot(up));
    high = std::max(high, p.dot(up));
  }
  const float span = std::max(1e-3f, high - low);
  const auto grey = [&](const Eigen::Vector3f& p) -> RgbColour {
    const auto level = static_cast<std::uint8_t>(
        std::lround(95.f + 125.f * std::clamp((p.dot(up) - low) / span, 0.f, 1.f)));
    return {level, level, level};
  };
  Splat(scene.structure_W, scene.structure_voxel_m, frame.camera, grey, config.region, 0.f, &raster);
  for (const PictureObject* object : others) {
    Splat(object->points_W, scene.object_voxel_m, frame.camera, grey, config.region, 0.f, &raster);
  }
  // Objects over the structure they stand on, small ones over the large ones they lie on.
  for (const PictureObject* object : shown) {
    const RgbColour colour = ClassColour(object->class_name);
    Eigen::AlignedBox3f box;
    for (const Eigen::Vector3f& p : object->points_W) box.extend(p);
    const float bias_m = box.isEmpty() || box.diagonal().norm() > 0.5f ? 0.01f : 0.02f;
    Splat(object->points_W, scene.object_voxel_m, frame.camera,
          [&](const Eigen::Vector3f&) { return colour; }, config.region, bias_m, &raster);
  }

  picture->width = config.width;
  picture->height = config.height;
  picture->rgb.assign(3 * pixels, 0);
  picture->camera = frame.camera;
  EyeDomeShade(raster, &picture->rgb);
  cv::Mat image(config.height, config.width, CV_8UC3, picture->rgb.data());

  // Legend entries: classes by count, then name.
  std::map<std::string, int> counts;
  for (const PictureObject* object : shown) ++counts[object->class_name];
  picture->legend.clear();
  for (const auto& [name, count] : counts) {
    picture->legend.push_back({name, count, ClassColour(name)});
  }
  std::stable_sort(picture->legend.begin(), picture->legend.end(),
                   [](const LegendEntry& a, const LegendEntry& b) { return a.count > b.count; });

  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = std::clamp(config.height / 1800.0, 0.35, 1.2);
  const int thickness = scale > 0.8 ? 2 : 1;
  std::vector<cv::Rect> taken;
  if (config.legend && !picture->legend.empty()) {
    int baseline = 0;
    const cv::Size row = cv::getTextSize("Mg", font, scale, thickness, &baseline);
    const int line = row.height + baseline + 8;
    int text_width = cv::getTextSize("objects", font, scale, thickness, &baseline).width;
    for (const LegendEntry& entry : picture->legend) {
      text_width = std::max(text_width, cv::getTextSize(entry.class_name + "  " + std::to_string(entry.count),
                                                        font, scale, thickness, &baseline).width);
    }
    const cv::Rect box(10, 10, text_width + line + 24,
                       line * static_cast<int>(picture->legend.size() + 1) + 8);
    cv::rectangle(image, box, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(image, box, cv::Scalar(120, 120, 120), 1);
    cv::putText(image, "objects", {box.x + 8, box.y + line - 6}, font, scale, cv::Scalar(0, 0, 0),
                thickness, cv::LINE_AA);
    for (std::size_t k = 0; k < picture->legend.size(); ++k) {
      const LegendEntry& entry = picture->legend[k];
      const int top = box.y + line * static_cast<int>(k + 1) + 4;
      cv::rectangle(image, cv::Rect(box.x + 8, top, line - 8, line - 8), Scalar(entry.colour),
                    cv::FILLED);
      cv::putText(image, entry.class_name + "  " + std::to_string(entry.count),
                  {box.x + line + 8, top + line - 12}, font, scale, cv::Scalar(0, 0, 0), thickness,
                  cv::LINE_AA);
    }
    taken.push_back(box);
  }
  picture->scale_bar_m = 0.0;
  picture->scale_bar_px = 0;
  if (config.scale_bar) {
    const double depth = std::max<double>(kNearM, (frame.camera.T_W_C.inverse() * frame.focus_W).z());
    const double metres_per_px = depth / frame.camera.fx;
    const double length = NiceLength(std::max(0.01, config.width / 8.0 * metres_per_px));
    const int px = static_cast<int>(std::lround(length / metres_per_px));
    if (px >= 4 && px < config.width - 40) {
      picture->scale_bar_m = length;
      picture->scale_bar_px = px;
      const int x0 = 20, y0 = config.height - 24;
      const std::string text =
          LengthText(length) + (config.view == PictureView::kTop ? "" : " at the centre");
      int baseline = 0;
      const cv::Size text_size = cv::getTextSize(text, font, scale, thickness, &baseline);
      const cv::Rect box(x0 - 8, y0 - text_size.height - 20, std::max(px, text_size.width) + 16,
                         text_size.height + 34);
      cv::rectangle(image, box, cv::Scalar(255, 255, 255), cv::FILLED);
      cv::rectangle(image, cv::Rect(x0, y0 - 4, px, 6), cv::Scalar(0, 0, 0), cv::FILLED);
      cv::putText(image, text, {x0, y0 - 12}, font, scale, cv::Scalar(0, 0, 0), thickness,
                  cv::LINE_AA);
      taken.push_back(box);
    }
  }
  if (config.labels) {
    for (const PictureObject* object : shown) {
      // Above the projection of the object's bounds (never over its middle).
      Eigen::AlignedBox3d box;
      for (const Eigen::Vector3f& p : object->points_W) {
        if (inside(p)) box.extend(p.cast<double>());
      }
      double u_sum = 0.0, v_min = std::numeric_limits<double>::max();
      int projected = 0;
      for (int corner = 0; corner < 8; ++corner) {
        const auto uv = frame.camera.Project(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(corner)));
        if (!uv) continue;
        u_sum += uv->x();
        v_min = std::min(v_min, uv->y());
        ++projected;
      }
      if (projected == 0) continue;
      char confidence[16];
      std::snprintf(confidence, sizeof confidence, "%.2f", object->confidence);
      const std::string text =
          object->class_name + " #" + std::to_string(object->id) + " " + confidence;
      int baseline = 0;
      const cv::Size text_size = cv::getTextSize(text, font, scale, thickness, &baseline);
      const cv::Size size(text_size.width + 10, text_size.height + baseline + 8);
      const cv::Point anchor(static_cast<int>(std::lround(u_sum / projected)),
                             static_cast<int>(std::lround(v_min)) - 4);
      const cv::Rect rect = PlaceLabel(size, anchor, image.size(), taken);
      taken.push_back(rect);
      cv::rectangle(image, rect, cv::Scalar(255, 255, 255), cv::FILLED);
      cv::rectangle(image, rect, Scalar(ClassColour(object->class_name)), thickness + 1);
      cv::putText(image, text, {rect.x + 5, rect.y + text_size.height + 4}, font, scale,
                  cv::Scalar(0, 0, 0), thickness, cv::LINE_AA);
    }
  }
  return true;
}

bool WritePicturePng(const MapPicture& picture, const std::string& path, std::string* why) {
  if (picture.rgb.size() != static_cast<std::size_t>(3 * picture.width * picture.height) ||
      picture.rgb.empty()) {
    *why = "the picture is empty";
    return false;
  }
  const cv::Mat rgb(picture.height, picture.width, CV_8UC3,
                    const_cast<std::uint8_t*>(picture.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  try {
    if (!cv::imwrite(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 6})) {
      *why = path + ": could not write the PNG (no such folder, or no permission)";
      return false;
    }
  } catch (const cv::Exception& error) {
    *why = path + ": " + error.what();
    return false;
  }
  return true;
}

std::optional<Eigen::Vector3d> UpFromCameras(const std::vector<Eigen::Isometry3d>& T_W_C) {
  if (T_W_C.empty()) return std::nullopt;
  // Cameras look down at tables and up at shelves, but are rarely rolled: their image-right
  // axes are horizontal whatever the pitch, so up is the direction most perpendicular to all of
  // them; the image-up axes only give its sign. Cameras that all face one way leave a plane of
  // such directions: then the image-up mean, made perpendicular to their right axis.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Vector3d image_up = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& pose : T_W_C) {
    const Eigen::Vector3d x = pose.linear().col(0);
    scatter += x * x.transpose();
    right += x;
    image_up -= pose.linear().col(1);
  }
  image_up /= static_cast<double>(T_W_C.size());
  if (!image_up.allFinite() || image_up.norm() < 0.5) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  Eigen::Vector3d up;
  if (eigen.eigenvalues()(1) > 0.05 * eigen.eigenvalues()(2)) {
    up = eigen.eigenvectors().col(0);
  } else {
    const Eigen::Vector3d across = right.normalized();
    up = image_up - across * across.dot(image_up);
  }
  if (!up.allFinite() || up.norm() < 1e-6) return std::nullopt;
  up.normalize();
  return up.dot(image_up) >= 0.0 ? up : -up;
}

}  // namespace objmap
