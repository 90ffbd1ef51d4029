#include "mapper/keyframe_segments.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <optional>

#include "segmentation/segment_index.h"

namespace objmap {
namespace {

bool Contains(const std::vector<int>& classes, int class_id) {
  return std::find(classes.begin(), classes.end(), class_id) != classes.end();
}

bool Inside(const BoundingBox2D& box, int u, int v) {
  return u >= box.x_min && u <= box.x_max && v >= box.y_min && v <= box.y_max;
}

// Value at `quantile` (0..1) of `values` (reordered; not empty).
float Quantile(std::vector<float>* values, float quantile) {
  const std::size_t k = std::min(
      values->size() - 1, static_cast<std::size_t>(quantile * static_cast<float>(values->size())));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(k),
                   values->end());
  return (*values)[k];
}

// A surface's top faces the image's up at least this much (PlaneFit::UpFacing).
constexpr float kMinUpFacing = 0.3f;
// Pieces of one table top: their centres lie within this distance of each other's plane, and
// their normals within acos(0.94) = 20 deg. Far below a table's height above the floor, and
// above the depth noise of a top 2-3 m away.
constexpr double kCoplanarDistanceM = 0.04;
constexpr double kCoplanarMinCos = 0.94;
// ... and each piece comes within this distance of another (camera frame): an object standing
// on a top cuts it up, while the top of another table beyond an aisle is as coplanar but
// farther away.
constexpr float kTopPieceGapM = 0.2f;
// Points per piece for that distance: spread over the piece, a few centimetres apart.
constexpr int kTopPieceSamples = 256;

// A table's top is the upper part of its box: what it holds up stands above it and its legs
// below. A top reaches into the upper quarter of the box; the floor seen between the legs, in
// the lower part, does not (when the top itself is not in view as a plane, for instance).
constexpr float kTopReachesBoxShare = 0.25f;

// A top spans at least this share of its box's width. A table seen at a grazing angle shows a
// thin band of top over a box that its legs make tall, so the share of the box's area says
// little; a book's top on it or a patch of floor between two legs spans a small part of the width.
constexpr float kTopMinWidthShare = 0.5f;

// A plane segment's centre and normal (turned towards the camera), camera frame.
struct PlaneFit {
  int segment = -1;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> samples;
  Eigen::Vector3f samples_min = Eigen::Vector3f::Zero();
  Eigen::Vector3f samples_max = Eigen::Vector3f::Zero();
  // How much it faces up in the image: the normal's image-up component (-y). A camera looking
  // level or down at a table (pitch below about 70 deg) sees its top facing up (> 0.3), while
  // a chair's back or a wall facing the camera faces down or sideways (<= 0): the camera frame
  // tells a top from a front without knowing which way the world's up is.
  [[nodiscard]] double UpFacing() const { return -normal.y(); }
};

// Some sample of `a` lies within `gap` of some sample of `b`.
bool PiecesMeet(const PlaneFit& a, const PlaneFit& b, float gap) {
  // Pieces whose sample bounds lie farther apart cannot meet: most pairs end here.
  if (((a.samples_min.array() - gap) > b.samples_max.array()).any() ||
      ((b.samples_min.array() - gap) > a.samples_max.array()).any()) {
    return false;
  }
  const float gap_sq = gap * gap;
  for (const Eigen::Vector3f& p : a.samples) {
    for (const Eigen::Vector3f& q : b.samples) {
      if ((p - q).squaredNorm() <= gap_sq) return true;
    }
  }
  return false;
}

bool FitPlane(const OrganizedCloud& cloud_C, const SegmentIndex& index, int s, PlaneFit* fit) {
  const int first = index.offsets[s], last = index.offsets[s + 1];
  // Every few pixels: a plane's normal needs no more.
  const int step = std::max(1, (last - first) / 2000);
  fit->samples.clear();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0;
  for (int k = first; k < last; k += step) {
    const int i = index.pixel_ids[k];
    if (!cloud_C.IsValid(i)) continue;
    const Eigen::Vector3d p = cloud_C.points_C[i].cast<double>();
    sum += p;
    outer += p * p.transpose();
    ++count;
  }
  if (count < 3) return false;
  const int sample_step = std::max(1, (last - first) / kTopPieceSamples);
  for (int k = first; k < last; k += sample_step) {
    const int i = index.pixel_ids[k];
    if (cloud_C.IsValid(i)) fit->samples.push_back(cloud_C.points_C[i]);
  }
  fit->samples_min = fit->samples_max = fit->samples.front();
  for (const Eigen::Vector3f& p : fit->samples) {
    fit->samples_min = fit->samples_min.cwiseMin(p);
    fit->samples_max = fit->samples_max.cwiseMax(p);
  }
  fit->segment = s;
  fit->centre = sum / count;
  const Eigen::Matrix3d covariance = outer / count - fit->centre * fit->centre.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  fit->normal = solver.eigenvectors().col(0);  // smallest eigenvalue
  if (fit->normal.dot(fit->centre) > 0.0) fit->normal = -fit->normal;
  return true;
}

// A table top is a supporting plane, so SelectDetectionPixels never returns it. Surface classes
// take the up-facing plane segments mostly inside the box (the floor or a wall seen beyond the
// table extends far outside it), grouped into tops: the pieces on one plane that meet (a top
// cut up by what stands on it is several plane segments). Of the tops that span half the box's
// width, reach into its upper quarter and hold a good share of its plane pixels (a quarter of
// the most any top holds), the one reaching highest is the table: a table's box ends at its
// top's far edge, while the floor between its legs and the top of a nearer table the box also
// holds lie lower, a book's top on the table is too narrow, and the floor seen beyond the
// table, which may reach higher, holds few of the box's pixels. A chair's back in front of the
// table faces the camera, not up.
std::vector<int> SurfacePlanePixels(const SegmentationResult& segmentation,
                                    const OrganizedCloud& cloud_C, const SegmentIndex& index,
                                    const BoundingBox2D& box) {
  std::vector<int> inside(segmentation.num_segments, 0);
  const int u0 = std::max(0, static_cast<int>(std::ceil(box.x_min)));
  const int v0 = std::max(0, static_cast<int>(std::ceil(box.y_min)));
  const int u1 = std::min(segmentation.width - 1, static_cast<int>(std::floor(box.x_max)));
  const int v1 = std::min(segmentation.height - 1, static_cast<int>(std::floor(box.y_max)));
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const int label = segmentation.labels[v * segmentation.width + u];
      if (label >= 0 && segmentation.segment_is_plane[label]) ++inside[label];
    }
  }
  std::vector<PlaneFit> tops;
  for (int s = 0; s < segmentation.num_segments; ++s) {
    const int total = segmentation.segment_is_plane[s] ? index.segments[s].pixels : 0;
    if (total == 0 || inside[s] * 2 < total) continue;
    PlaneFit fit;
    if (FitPlane(cloud_C, index, s, &fit) && fit.UpFacing() >= kMinUpFacing) tops.push_back(fit);
  }
  std::sort(tops.begin(), tops.end(),
            [](const PlaneFit& a, const PlaneFit& b) { return a.centre.z() < b.centre.z(); });
  // Which pieces meet, once: every seed's growth asks again.
  std::vector<std::vector<bool>> meet(tops.size(), std::vector<bool>(tops.size(), false));
  for (std::size_t i = 0; i < tops.size(); ++i) {
    for (std::size_t k = i + 1; k < tops.size(); ++k) {
      meet[i][k] = meet[k][i] = PiecesMeet(tops[i], tops[k], kTopPieceGapM);
    }
  }
  struct Top {
    std::vector<std::size_t> pieces;  // indices into `tops`
    int v_min = 0;
    int inside = 0;
  };
  std::vector<Top> found;
  int most_inside = 0;
  const float box_width = std::min<float>(segmentation.width, box.x_max) - std::max(0.f, box.x_min);
  for (const PlaneFit& seed : tops) {
    // The seed's top grows by coplanar pieces near a piece it has (breadth first).
    std::vector<std::size_t> members = {static_cast<std::size_t>(&seed - tops.data())};
    std::vector<bool> taken(tops.size(), false);
    taken[members.front()] = true;
    for (std::size_t next = 0; next < members.size(); ++next) {
      for (std::size_t k = 0; k < tops.size(); ++k) {
        const PlaneFit& piece = tops[k];
        if (taken[k] || !meet[members[next]][k] ||
            std::abs(seed.normal.dot(piece.centre - seed.centre)) > kCoplanarDistanceM ||
            seed.normal.dot(piece.normal) < kCoplanarMinCos) {
          continue;
        }
        taken[k] = true;
        members.push_back(k);
      }
    }
    int u_min = segmentation.width, v_min = segmentation.height, u_max = -1, v_max = -1;
    for (std::size_t k : members) {
      const SegmentIndex::Segment& extent = index.segments[tops[k].segment];
      u_min = std::min(u_min, extent.u_min), u_max = std::max(u_max, extent.u_max);
      v_min = std::min(v_min, extent.v_min), v_max = std::max(v_max, extent.v_max);
    }
    const float width = std::min<float>(u_max + 1, box.x_max) - std::max<float>(u_min, box.x_min);
    if (width < kTopMinWidthShare * box_width ||
        v_min > box.y_min + kTopReachesBoxShare * box.Height()) {
      continue;
    }
    Top top{std::move(members), v_min, 0};
    for (std::size_t k : top.pieces) top.inside += inside[tops[k].segment];
    most_inside = std::max(most_inside, top.inside);
    found.push_back(std::move(top));
  }
  // Seeds go nearest first, so of two tops reaching as high the nearer one stays.
  const Top* best = nullptr;
  for (const Top& top : found) {
    if (top.inside * 4 < most_inside) continue;
    if (best == nullptr || top.v_min < best->v_min) best = &top;
  }
  if (best == nullptr) return {};
  std::vector<int> pixels;
  for (std::size_t k : best->pieces) {
    const int s = tops[k].segment;
    pixels.insert(pixels.end(), index.pixel_ids.begin() + index.offsets[s],
                  index.pixel_ids.begin() + index.offsets[s + 1]);
  }
  std::sort(pixels.begin(), pixels.end());
  return pixels;
}

// Flat objects (a screen on a wall, a keyboard on a desk) lie within depth noise of their
// supporting plane, so no segment separates them (the paper's lost keyboards). When one plane
// segment covers most of the box, the object is the part of that plane the box covers, shrunk
// by `shrink_fraction` on every side because colour and depth are not registered. With
// `planes_only` false the dominant segment may be any segment: a wall the segmentation did not
// take for a supporting plane (cupboards around it) still carries the screen hung on it.
std::vector<int> FlatObjectPixels(const SegmentationResult& segmentation, const BoundingBox2D& box,
                                  float shrink_fraction, bool planes_only) {
  const float du = shrink_fraction * box.Width();
  const float dv = shrink_fraction * box.Height();
  const int u0 = std::max(0, static_cast<int>(std::ceil(box.x_min + du)));
  const int v0 = std::max(0, static_cast<int>(std::ceil(box.y_min + dv)));
  const int u1 = std::min(segmentation.width - 1, static_cast<int>(box.x_max - du));
  const int v1 = std::min(segmentation.height - 1, static_cast<int>(box.y_max - dv));
  std::vector<int> count(segmentation.num_segments, 0);
  int valid = 0;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const int label = segmentation.labels[v * segmentation.width + u];
      if (label < 0) continue;
      ++valid;
      if (!planes_only || segmentation.segment_is_plane[label]) ++count[label];
    }
  }
  std::vector<int> pixels;
  if (count.empty()) return pixels;
  const int plane = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  if (count[plane] * 2 < valid) return pixels;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      if (segmentation.labels[v * segmentation.width + u] == plane) {
        pixels.push_back(v * segmentation.width + u);
      }
    }
  }
  return pixels;
}

// Keeps the pixels inside the box grown by the detection-segment dilation. A segment that runs
// beyond its box (two chairs side by side in one segment) cannot belong to the detection there.
std::vector<int> CropToBox(std::vector<int> pixels, const BoundingBox2D& box, int width,
                           const DetectionSegmentConfig& config) {
  const BoundingBox2D grown = DilateDetectionBox(box, config);
  pixels.erase(std::remove_if(pixels.begin(), pixels.end(),
                              [&](int i) {
                                const int v = i / width;
                                return !Inside(grown, i - v * width, v);
                              }),
               pixels.end());
  return pixels;
}

// The pixels of one detection: supporting surfaces take their plane, flat objects the part of
// the plane in their box, everything else the segments SelectDetectionPixels picks.
// Share of `box` that the bounding box of `pixels` covers.
float BoxFill(const std::vector<int>& pixels, int width, const BoundingBox2D& box) {
  if (pixels.empty() || !(box.Area() > 0.f)) return 0.f;
  int u_min = width, v_min = std::numeric_limits<int>::max(), u_max = -1, v_max = -1;
  for (int i : pixels) {
    const int v = i / width, u = i - v * width;
    u_min = std::min(u_min, u), u_max = std::max(u_max, u);
    v_min = std::min(v_min, v), v_max = std::max(v_max, v);
  }
  // Pixel boxes are inclusive: a segment of one pixel spans 1 x 1.
  const float w = std::min<float>(u_max + 1, box.x_max) - std::max<float>(u_min, box.x_min);
  const float h = std::min<float>(v_max + 1, box.y_max) - std::max<float>(v_min, box.y_min);
  if (w <= 0.f || h <= 0.f) return 0.f;
  return std::min(1.f, w * h / box.Area());
}

// `is_top` tells a surface class's top (SurfacePlanePixels), which has passed its own test of
// how much of the box it spans.
std::vector<int> DetectionPixels(const SegmentationResult& segmentation,
                                 const OrganizedCloud& cloud_C, const SegmentIndex& index,
                                 const BoundingBox2D& box, int class_id, const MapperConfig& config,
                                 bool* is_top) {
  *is_top = false;
  if (Contains(config.surface_classes, class_id)) {
    std::vector<int> pixels = SurfacePlanePixels(segmentation, cloud_C, index, box);
    if (!pixels.empty()) {
      *is_top = true;
      return pixels;
    }
  }
  const bool flat = Contains(config.flat_classes, class_id);
  if (flat) {
    std::vector<int> pixels =
        FlatObjectPixels(segmentation, box, config.flat_box_shrink_fraction, true);
    if (!pixels.empty()) return pixels;
  }
  std::vector<int> pixels =
      SelectDetectionPixels(segmentation, index, box, config.detection_segment);
  if (flat && BoxFill(pixels, segmentation.width, box) < config.min_segment_box_fill) {
    // Only a fragment of the box stands out from its surroundings: the flat object is the part
    // of the surface that fills its box.
    std::vector<int> surface =
        FlatObjectPixels(segmentation, box, config.flat_box_shrink_fraction, false);
    if (!surface.empty()) return surface;
  }
  return pixels;
}

// The observation's points from the keyframe's depth as stored, with the pixels they came from:
// the store keeps those and rebuilds the same points from the same depth.
void SetSegment(const OrganizedCloud& cloud_C, const std::vector<std::uint16_t>& depth_mm,
                const CameraIntrinsics& intrinsics, const std::vector<int>& pixels,
                float voxel_size_m, ObjectObservation* observation) {
  observation->segment_pixels = RunsOf(pixels);
  observation->segment_voxel_size_m = voxel_size_m;
  observation->segment_C =
      SegmentPointsFromDepth(depth_mm, intrinsics, observation->segment_pixels, voxel_size_m,
                             cloud_C.rgb.empty() ? nullptr : &cloud_C.rgb);
}

// The pixels one observation claimed, as a bit per pixel of the frame: cheaper to build and to
// query than a hash set of up to a few 10^4 pixel indices per detection.
class PixelClaim {
 public:
  PixelClaim(const std::vector<int>& pixels, std::size_t frame_pixels) : bits_(frame_pixels) {
    for (int i : pixels) bits_[i] = true;
  }
  [[nodiscard]] bool Has(int i) const { return bits_[i]; }

 private:
  std::vector<bool> bits_;
};

// Fraction of `pixels` already claimed by `claimed`.
float ClaimedFraction(const std::vector<int>& pixels, const PixelClaim& claimed) {
  if (pixels.empty()) return 0.f;
  const auto hits =
      std::count_if(pixels.begin(), pixels.end(), [&](int i) { return claimed.Has(i); });
  return static_cast<float>(hits) / static_cast<float>(pixels.size());
}

// How far (u, v) lies from the box centre, in half-extents (< 1 inside the box).
float BoxDistance(const BoundingBox2D& box, int u, int v) {
  const float half_w = std::max(0.5f, 0.5f * box.Width());
  const float half_h = std::max(0.5f, 0.5f * box.Height());
  return std::max(std::abs(u - 0.5f * (box.x_min + box.x_max)) / half_w,
                  std::abs(v - 0.5f * (box.y_min + box.y_max)) / half_h);
}

// The pixels of two same-class detections that picked one segment (two cups touching, a stack
// of books), shared out: a pixel in one box only goes to it, any other to the box whose centre is
// nearer in units of the box's half-size.
void SplitBetweenBoxes(const std::vector<int>& pixels, int width, const BoundingBox2D& box_a,
                       const BoundingBox2D& box_b, std::vector<int>* pixels_a,
                       std::vector<int>* pixels_b) {
  for (int i : pixels) {
    const int u = i % width, v = i / width;
    const bool in_a = Inside(box_a, u, v), in_b = Inside(box_b, u, v);
    const bool to_a = in_a != in_b ? in_a : BoxDistance(box_a, u, v) <= BoxDistance(box_b, u, v);
    (to_a ? pixels_a : pixels_b)->push_back(i);
  }
}

void AddClassScore(ObjectObservation* observation, int class_id, float score) {
  for (auto& [existing_class, existing_score] : observation->class_scores) {
    if (existing_class == class_id) {
      existing_score = std::max(existing_score, score);  // the same object detected twice
      return;
    }
  }
  observation->class_scores.emplace_back(class_id, score);
}

// The up direction, camera frame, where `box` stands: the normal of the up-facing supporting
// plane with most pixels around the box (what holds an object up shows around and below it,
// and often inside its box), and the plane's height along it. False when no up-facing plane is
// in sight there.
bool SupportUpNear(const SegmentationResult& segmentation, const OrganizedCloud& cloud_C,
                   const SegmentIndex& index, const BoundingBox2D& box, Eigen::Vector3d* up,
                   float* height) {
  const float du = 0.5f * box.Width(), dv = box.Height();
  const int u0 = std::max(0, static_cast<int>(box.x_min - du));
  const int v0 = std::max(0, static_cast<int>(box.y_min - dv));
  const int u1 = std::min(segmentation.width - 1, static_cast<int>(box.x_max + du));
  const int v1 = std::min(segmentation.height - 1, static_cast<int>(box.y_max + dv));
  std::vector<std::pair<int, int>> planes;  // (pixels around the box, segment)
  {
    std::vector<int> count(segmentation.num_segments, 0);
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        const int label = segmentation.labels[v * segmentation.width + u];
        if (label >= 0 && segmentation.segment_is_plane[label]) ++count[label];
      }
    }
    for (int s = 0; s < segmentation.num_segments; ++s) {
      if (count[s] > 0) planes.emplace_back(count[s], s);
    }
  }
  std::sort(planes.rbegin(), planes.rend());
  for (const auto& [pixels, s] : planes) {
    PlaneFit fit;
    if (FitPlane(cloud_C, index, s, &fit) && fit.UpFacing() > kMinUpFacing) {
      *up = fit.normal;
      *height = static_cast<float>(fit.normal.dot(fit.centre));
      return true;
    }
  }
  return false;
}

// A layer's pixels reach this far beyond the heights its boxes' own pixels span (depth noise).
constexpr float kLayerSpanMarginM = 0.005f;
// A box's own pixels (in no other box of the stack) that place it by their median height.
constexpr std::size_t kMinOwnPixels = 20;
// Points less than this above the supporting plane are the plane's (its depth noise at 2-3 m),
// not the stack's lowest layer.
constexpr float kAboveSupportM = 0.005f;

// A stack's boxes with the pixels of its segment that their detections picked.
struct StackGroup {
  std::vector<BoundingBox2D> boxes;  // depth pixels; the first is the group's first entry's
  std::vector<BoundingBox2D> detection_boxes;  // the same, as detected (colour pixels)
  std::vector<float> scores;
  std::vector<int> pixels;  // union over the boxes, each pixel once
};

// One layer of a stack per distinct box: the pixels at its height, with the box and score of
// the detections it stands for (ascending height). Empty when the stack cannot be cut: no
// up-facing support in sight, or every box at one height (one object boxed several times).
struct StackLayer {
  std::vector<int> pixels;
  std::vector<int> boxes;  // indices into StackGroup::boxes
};
std::vector<StackLayer> CutStack(const SegmentationResult& segmentation,
                                 const OrganizedCloud& cloud_C, const SegmentIndex& index,
                                 const StackGroup& group, float min_layer_gap_m) {
  std::vector<StackLayer> layers;
  BoundingBox2D all = group.boxes.front();
  for (const BoundingBox2D& b : group.boxes) {
    all = {std::min(all.x_min, b.x_min), std::min(all.y_min, b.y_min), std::max(all.x_max, b.x_max),
           std::max(all.y_max, b.y_max)};
  }
  Eigen::Vector3d up;
  float support_height = 0.f;
  if (!SupportUpNear(segmentation, cloud_C, index, all, &up, &support_height)) return layers;
  const int width = segmentation.width;
  // Each pixel's height above the support, once; NaN for no depth and for the support itself
  // (the desk around the stack's foot), which is no layer's.
  const Eigen::Vector3f up_f = up.cast<float>();
  std::vector<float> height_of(group.pixels.size(), std::numeric_limits<float>::quiet_NaN());
  for (std::size_t p = 0; p < group.pixels.size(); ++p) {
    const int i = group.pixels[p];
    if (!cloud_C.IsValid(i)) continue;
    const float h = up_f.dot(cloud_C.points_C[i]);
    if (h >= support_height + kAboveSupportM) height_of[p] = h;
  }
  // Each box's height: the median over the pixels only it covers (a lower book's side strip,
  // the top book's cover), robust to a few pixels of jitter in boxes a few pixels high. A box
  // with too few of its own (the middle of three, covered by the boxes above and below it)
  // lies between its neighbours in the image, lower in the image being lower in the stack.
  const std::size_t count = group.boxes.size();
  std::vector<float> own_median(count, std::numeric_limits<float>::quiet_NaN());
  // The heights a box's own pixels span (the middle 90 %): where its object certainly is.
  std::vector<std::pair<float, float>> own_span(
      count, {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::quiet_NaN()});
  std::vector<float> inside_median(count, std::numeric_limits<float>::quiet_NaN());
  for (std::size_t b = 0; b < count; ++b) {
    std::vector<float> own, inside;
    for (std::size_t p = 0; p < group.pixels.size(); ++p) {
      const float h = height_of[p];
      const int i = group.pixels[p], v = i / width, u = i - v * width;
      if (std::isnan(h) || !Inside(group.boxes[b], u, v)) continue;
      inside.push_back(h);
      bool shared = false;
      for (std::size_t o = 0; o < count && !shared; ++o) {
        shared = o != b && Inside(group.boxes[o], u, v);
      }
      if (!shared) own.push_back(h);
    }
    if (own.size() >= kMinOwnPixels) {
      own_median[b] = Quantile(&own, 0.5f);
      std::sort(own.begin(), own.end());
      own_span[b] = {own[own.size() / 20], own[own.size() - 1 - own.size() / 20]};
    }
    if (!inside.empty()) inside_median[b] = Quantile(&inside, 0.5f);
  }
  std::vector<int> image_order(count);  // lowest in the image first
  std::iota(image_order.begin(), image_order.end(), 0);
  std::sort(image_order.begin(), image_order.end(), [&](int a, int b) {
    return group.boxes[a].y_min + group.boxes[a].y_max >
           group.boxes[b].y_min + group.boxes[b].y_max;
  });
  std::vector<std::pair<float, int>> box_heights;
  for (std::size_t k = 0; k < count; ++k) {
    const int b = image_order[k];
    float height = own_median[b];
    if (std::isnan(height)) {
      float below = std::numeric_limits<float>::quiet_NaN(), above = below;
      for (std::size_t n = k; n-- > 0 && std::isnan(below);) below = own_median[image_order[n]];
      for (std::size_t n = k + 1; n < count && std::isnan(above); ++n) {
        above = own_median[image_order[n]];
      }
      height = !std::isnan(below) && !std::isnan(above) ? 0.5f * (below + above) : inside_median[b];
    }
    if (!std::isnan(height)) box_heights.emplace_back(height, b);
  }
  std::sort(box_heights.begin(), box_heights.end());
  std::vector<float> layer_height;
  for (const auto& [h, b] : box_heights) {
    if (layer_height.empty() || h - layer_height.back() >= min_layer_gap_m) {
      layer_height.push_back(h);
      layers.emplace_back();
    }
    layers.back().boxes.push_back(b);
  }
  if (layers.size() < 2) return {};
  // A layer reaches as far as its boxes' own pixels do. Between two layers' spans lies what no
  // box claimed alone: a book of the stack the detector did not box in this view, which belongs
  // to neither neighbour.
  std::vector<float> layer_lo(layers.size(), std::numeric_limits<float>::lowest());
  std::vector<float> layer_hi(layers.size(), std::numeric_limits<float>::max());
  for (std::size_t l = 0; l < layers.size(); ++l) {
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    for (int b : layers[l].boxes) {
      if (std::isnan(own_span[b].first)) continue;
      lo = std::min(lo, own_span[b].first);
      hi = std::max(hi, own_span[b].second);
    }
    if (lo <= hi) layer_lo[l] = lo - kLayerSpanMarginM, layer_hi[l] = hi + kLayerSpanMarginM;
  }
  // Each pixel goes to the layer whose height it lies nearest: the cuts halfway between layers.
  for (std::size_t p = 0; p < group.pixels.size(); ++p) {
    const float h = height_of[p];
    if (std::isnan(h)) continue;
    std::size_t l = 0;
    while (l + 1 < layer_height.size() && h > 0.5f * (layer_height[l] + layer_height[l + 1])) ++l;
    if (h >= layer_lo[l] && h <= layer_hi[l]) layers[l].pixels.push_back(group.pixels[p]);
  }
  return layers;
}

}  // namespace

bool IsPartOfAnotherDetection(const std::vector<Detection>& detections, std::size_t d,
                              const MapperConfig& config) {
  const Detection& part = detections[d];
  if (!Contains(config.part_classes, part.class_id)) return false;
  for (std::size_t w = 0; w < detections.size(); ++w) {
    const Detection& whole = detections[w];
    if (w == d || whole.score < config.min_detection_score ||
        !Contains(config.whole_classes, whole.class_id)) {
      continue;
    }
    if (BoxInsideFraction(part.box, whole.box) >= config.part_inside_fraction &&
        whole.box.Area() >= config.min_whole_to_part_area * part.box.Area()) {
      return true;
    }
  }
  return false;
}

BoundingBox2D ToDepthPixels(const BoundingBox2D& box, const ColorImage& color,
                            const DepthImage& depth) {
  if (color.empty() || (color.width == depth.width && color.height == depth.height)) return box;
  const float sx = static_cast<float>(depth.width) / color.width;
  const float sy = static_cast<float>(depth.height) / color.height;
  return {box.x_min * sx, box.y_min * sy, box.x_max * sx, box.y_max * sy};
}

std::vector<SegmentedDetection> SegmentDetections(
    const RgbdFrame& frame, const OrganizedCloud& cloud_C,
    const std::vector<std::uint16_t>& depth_mm, const SegmentationResult& segmentation,
    const SegmentIndex& index, const std::vector<Detection>& detections, KeyframeId keyframe_id,
    const MapperConfig& config) {
  std::vector<int> order(detections.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return detections[a].score > detections[b].score; });
  std::vector<SegmentedDetection> segmented;
  const std::size_t frame_pixels = segmentation.labels.size();
  std::vector<PixelClaim> claimed;
  std::vector<BoundingBox2D> depth_boxes;  // of each entry, in depth pixels
  // Detections of a stack class that picked one segment: the entry each grew from (its root)
  // and, per root, the group the stack is cut from once every detection has been seen.
  std::vector<std::size_t> root_of;
  std::map<std::size_t, StackGroup> stacks;
  auto add_to_stack = [&](std::size_t root, const Detection& detection, const BoundingBox2D& box,
                          const std::vector<int>& pixels) {
    StackGroup& group = stacks[root];
    group.boxes.push_back(box);
    group.detection_boxes.push_back(detection.box);
    group.scores.push_back(detection.score);
    group.pixels.insert(group.pixels.end(), pixels.begin(), pixels.end());
  };
  auto make_entry = [&](const Detection& detection, const std::vector<int>& pixels,
                        SegmentedDetection* entry) {
    SetSegment(cloud_C, depth_mm, frame.intrinsics, pixels, config.objects.model_voxel_size_m,
               &entry->observation);
    if (static_cast<int>(entry->observation.segment_C.size()) < config.min_segment_points) {
      return false;
    }
    entry->observation.keyframe_id = keyframe_id;
    entry->observation.box = detection.box;
    entry->observation.class_scores = {{detection.class_id, detection.score}};
    entry->pixels = pixels;
    return true;
  };
  for (int d : order) {
    const Detection& detection = detections[d];
    if (detection.score < config.min_detection_score || detection.box.Area() <= 0.f) continue;
    if (IsPartOfAnotherDetection(detections, d, config)) continue;
    const BoundingBox2D box = ToDepthPixels(detection.box, frame.color, frame.depth);
    bool is_top = false;
    const std::vector<int> pixels = CropToBox(
        DetectionPixels(segmentation, cloud_C, index, box, detection.class_id, config, &is_top),
        box, segmentation.width, config.detection_segment);
    if (pixels.empty() ||
        (!is_top && BoxFill(pixels, segmentation.width, box) < config.min_segment_box_fill)) {
      continue;
    }
    bool handled = false;
    for (std::size_t k = 0; k < segmented.size() && !handled; ++k) {
      if (ClaimedFraction(pixels, claimed[k]) < 0.5f) continue;
      ObjectObservation& earlier = segmented[k].observation;
      // What lies on a table is not the table, though its pixels are part of the table's plane
      // (a flat keyboard within the plane's depth noise).
      if (Contains(config.surface_classes, earlier.class_scores.front().first) &&
          !Contains(config.surface_classes, detection.class_id)) {
        continue;
      }
      handled = true;
      const bool same_class = earlier.class_scores.front().first == detection.class_id;
      if (same_class && stacks.count(root_of[k]) > 0) {
        add_to_stack(root_of[k], detection, box, pixels);
      }
      if (same_class && BoxIoU(depth_boxes[k], box) < config.split_max_box_iou) {
        std::vector<int> joined = segmented[k].pixels;
        for (int i : pixels) {
          if (!claimed[k].Has(i)) joined.push_back(i);
        }
        std::vector<int> pixels_k, pixels_d;
        SplitBetweenBoxes(joined, segmentation.width, depth_boxes[k], box, &pixels_k, &pixels_d);
        SegmentedDetection kept, added;
        if (make_entry(detection, pixels_d, &added) && make_entry(detection, pixels_k, &kept)) {
          kept.observation.box = earlier.box;
          kept.observation.class_scores = earlier.class_scores;
          segmented[k] = std::move(kept);
          claimed[k] = PixelClaim(pixels_k, frame_pixels);
          claimed.emplace_back(pixels_d, frame_pixels);
          depth_boxes.push_back(box);
          root_of.push_back(root_of[k]);
          segmented.push_back(std::move(added));
          continue;
        }
      }
      AddClassScore(&earlier, detection.class_id, detection.score);
    }
    if (handled) continue;
    SegmentedDetection entry;
    if (!make_entry(detection, pixels, &entry)) continue;
    claimed.emplace_back(pixels, frame_pixels);
    depth_boxes.push_back(box);
    root_of.push_back(segmented.size());
    if (Contains(config.stack_classes, detection.class_id) && !is_top) {
      add_to_stack(segmented.size(), detection, box, pixels);
    }
    segmented.push_back(std::move(entry));
  }
  // Stacks seen as one segment: each distinct box takes its layer, replacing whatever the
  // split by box made of them.
  std::vector<bool> replaced(segmented.size(), false);
  std::vector<SegmentedDetection> layered;
  for (auto& [root, group] : stacks) {
    if (group.boxes.size() < 2) continue;
    std::sort(group.pixels.begin(), group.pixels.end());
    group.pixels.erase(std::unique(group.pixels.begin(), group.pixels.end()), group.pixels.end());
    const std::vector<StackLayer> layers =
        CutStack(segmentation, cloud_C, index, group, config.min_stack_layer_gap_m);
    std::vector<SegmentedDetection> entries;
    for (const StackLayer& layer : layers) {
      // The layer speaks for its best-scoring box; the group's first box keeps what its entry
      // gathered from other classes' detections of the same segment.
      const std::vector<float>& scores = group.scores;  // a structured binding is not captured
      const int best = *std::max_element(layer.boxes.begin(), layer.boxes.end(),
                                         [&scores](int a, int b) { return scores[a] < scores[b]; });
      Detection detection;
      detection.class_id = segmented[root].observation.class_scores.front().first;
      detection.score = group.scores[best];
      detection.box = group.detection_boxes[best];
      SegmentedDetection entry;
      if (!make_entry(detection, layer.pixels, &entry)) break;
      if (std::find(layer.boxes.begin(), layer.boxes.end(), 0) != layer.boxes.end()) {
        entry.observation.class_scores = segmented[root].observation.class_scores;
      }
      entries.push_back(std::move(entry));
    }
    if (entries.size() != layers.size() || layers.empty()) continue;  // kept as split by box
    for (std::size_t e = 0; e < segmented.size(); ++e) {
      if (root_of[e] == root) replaced[e] = true;
    }
    for (SegmentedDetection& entry : entries) layered.push_back(std::move(entry));
  }
  std::vector<SegmentedDetection> result;
  for (std::size_t e = 0; e < segmented.size(); ++e) {
    if (!replaced[e]) result.push_back(std::move(segmented[e]));
  }
  for (SegmentedDetection& entry : layered) result.push_back(std::move(entry));
  return result;
}

namespace {

// Depths and extents of a segment are read from its 5th to 95th percentiles: a few flying pixels
// at its border would otherwise make a mug half a metre tall.
constexpr float kLowQuantile = 0.05f;
constexpr float kHighQuantile = 0.95f;

// A surface a segment holds up shows within this many pixels above its top edge: the board's
// edge (a few centimetres) lies between a table's top and its leg.
constexpr int kSurfaceSearchPx = 12;

}  // namespace

std::vector<SegmentedDetection> UnclassifiedSegments(
    const RgbdFrame& frame, const OrganizedCloud& cloud_C,
    const std::vector<std::uint16_t>& depth_mm, const SegmentationResult& segmentation,
    const SegmentIndex& index, const std::vector<Detection>& detections,
    const std::vector<SegmentedDetection>& detected, KeyframeId keyframe_id,
    const MapperConfig& config) {
  const UnknownObjectConfig& unknown = config.unknown_objects;
  std::vector<SegmentedDetection> result;
  if (!unknown.enabled || segmentation.num_segments == 0) return result;
  if (!index.Matches(segmentation)) return result;
  const int width = segmentation.width, height = segmentation.height;
  std::vector<std::uint8_t> claimed(segmentation.labels.size(), 0);
  for (const SegmentedDetection& entry : detected) {
    for (int i : entry.pixels) claimed[i] = 1;
  }
  struct NamedBox {
    BoundingBox2D box;  // dilated, depth pixels
    bool surface = false;
  };
  std::vector<NamedBox> boxes;
  for (const Detection& detection : detections) {
    if (detection.score < config.min_detection_score || detection.box.Area() <= 0.f) continue;
    boxes.push_back({DilateDetectionBox(ToDepthPixels(detection.box, frame.color, frame.depth),
                                        config.detection_segment),
                     Contains(config.surface_classes, detection.class_id)});
  }
  const float sx = frame.color.empty() ? 1.f : static_cast<float>(frame.color.width) / width;
  const float sy = frame.color.empty() ? 1.f : static_cast<float>(frame.color.height) / height;
  const int margin = unknown.image_border_px;
  // Up-facing planes, fitted once each when a candidate first meets them (nullopt: not up-facing).
  std::map<int, std::optional<PlaneFit>> plane_fits;
  auto up_facing_plane = [&](int p) -> const std::optional<PlaneFit>& {
    auto it = plane_fits.find(p);
    if (it != plane_fits.end()) return it->second;
    PlaneFit fit;
    std::optional<PlaneFit> result;
    if (FitPlane(cloud_C, index, p, &fit) && fit.UpFacing() > kMinUpFacing) result = fit;
    return plane_fits.emplace(p, std::move(result)).first->second;
  };
  struct Candidate {
    int segment = -1;
    Eigen::Vector3d up = Eigen::Vector3d::Zero();
    float support_height = 0.f;
    // Its top edge: its pixels whose neighbour above belongs to something else.
    std::vector<int> top_edge;
  };
  std::vector<Candidate> candidates;
  std::vector<int> candidate_of(segmentation.num_segments, -1);
  std::vector<float> heights;
  for (int s = 0; s < segmentation.num_segments; ++s) {
    const SegmentIndex::Segment& segment = index.segments[s];
    if (segmentation.segment_is_plane[s] || segment.pixels < unknown.min_segment_px) continue;
    // Cut off by the image: a part of something larger, seen whole from elsewhere.
    if (segment.u_min < margin || segment.v_min < margin || segment.u_max >= width - margin ||
        segment.v_max >= height - margin) {
      continue;
    }
    const int first = index.offsets[s], last = index.offsets[s + 1];
    int claimed_pixels = 0;
    for (int k = first; k < last; ++k) claimed_pixels += claimed[index.pixel_ids[k]];
    if (static_cast<float>(claimed_pixels) >
        unknown.max_claimed_fraction * static_cast<float>(last - first)) {
      continue;
    }
    // Inside a named object's box: a part of it. What stands on a table lies in the upper part
    // of the table's box; its legs and what is under it, in the lower half.
    const float centre_v = 0.5f * static_cast<float>(segment.v_min + segment.v_max);
    bool part_of_named = false;
    for (const NamedBox& named : boxes) {
      if (named.box.x_max < segment.u_min || named.box.x_min > segment.u_max ||
          named.box.y_max < segment.v_min || named.box.y_min > segment.v_max) {
        continue;
      }
      int inside = 0;
      for (int k = first; k < last; ++k) {
        const int i = index.pixel_ids[k];
        inside += Inside(named.box, i % width, i / width) ? 1 : 0;
      }
      if (inside * 2 < last - first) continue;
      const float box_middle_v = 0.5f * (named.box.y_min + named.box.y_max);
      if (!named.surface || centre_v > box_middle_v) {
        part_of_named = true;
        break;
      }
    }
    if (part_of_named) continue;
    const BoundingBox2D box{static_cast<float>(segment.u_min), static_cast<float>(segment.v_min),
                            static_cast<float>(segment.u_max), static_cast<float>(segment.v_max)};
    Candidate candidate;
    candidate.segment = s;
    if (!SupportUpNear(segmentation, cloud_C, index, box, &candidate.up,
                       &candidate.support_height)) {
      continue;
    }
    heights.clear();
    for (int k = first; k < last; ++k) {
      const int i = index.pixel_ids[k];
      if (!cloud_C.IsValid(i)) continue;
      heights.push_back(static_cast<float>(candidate.up.dot(cloud_C.points_C[i].cast<double>())) -
                        candidate.support_height);
    }
    if (static_cast<int>(heights.size()) < unknown.min_segment_px) continue;
    // It stands on the support (its foot at the plane's height) and rises above its noise.
    const float foot = Quantile(&heights, kLowQuantile);
    const float top = Quantile(&heights, kHighQuantile);
    if (std::abs(foot) > unknown.max_support_gap_m || top < unknown.min_height_m) continue;
    for (int k = first; k < last; ++k) {
      const int i = index.pixel_ids[k];
      if (i >= width && segmentation.labels[i - width] != s) candidate.top_edge.push_back(i);
    }
    // A leg holds up a surface: within a few pixels above its top edge (the board's edge
    // between), an up-facing plane at or above its top. A part of the furniture (a table, a
    // stool, a chair's seat), which the surface's own object or another view names.
    bool under_a_surface = false;
    for (std::size_t e = 0; e < candidate.top_edge.size() && !under_a_surface; ++e) {
      const int i = candidate.top_edge[e];
      int label = -1;
      for (int j = i - width, step = 0; j >= 0 && step < kSurfaceSearchPx; j -= width, ++step) {
        const int above = segmentation.labels[j];
        if (above >= 0 && above != s && segmentation.segment_is_plane[above]) {
          label = above;
          break;
        }
      }
      if (label < 0) continue;
      const std::optional<PlaneFit>& plane = up_facing_plane(label);
      if (!plane) continue;
      const float plane_height =
          static_cast<float>(candidate.up.dot(plane->centre)) - candidate.support_height;
      under_a_surface =
          plane_height > unknown.min_height_m && plane_height >= top - unknown.max_support_gap_m;
    }
    if (under_a_surface) continue;
    // Hidden along a third or more of its top edge by something nearer (the far legs of a stool
    // behind its seat, a mug behind a box): like a segment at the image border, only a part of
    // it is in view.
    int top_edge = 0, hidden_top_edge = 0;
    for (const int i : candidate.top_edge) {
      if (!cloud_C.IsValid(i)) continue;
      ++top_edge;
      const float z = cloud_C.points_C[i].z();
      const float z_above = cloud_C.IsValid(i - width) ? cloud_C.points_C[i - width].z() : z;
      if (z_above < z * (1.f - config.segmenter.depth_jump_ratio)) ++hidden_top_edge;
    }
    if (hidden_top_edge * 3 > top_edge) continue;
    candidate_of[s] = static_cast<int>(candidates.size());
    candidates.push_back(std::move(candidate));
  }
  if (candidates.empty()) return result;

  // A thing of its own is free at its top: above its top edge lies what is behind it (a wall,
  // the surface it stands on) or another candidate it is part of. A segment that continues
  // upwards, without a depth step, into something else along a third or more of its top edge
  // is attached to it: a table's or a stool's leg under its top or apron, a drawer in a
  // cabinet, the foot of a wall.
  auto free_at_top = [&](const Candidate& candidate) {
    int top_edge = 0, attached = 0;
    for (const int i : candidate.top_edge) {
      if (!cloud_C.IsValid(i) || !cloud_C.IsValid(i - width)) continue;
      const int label = segmentation.labels[i - width];
      ++top_edge;
      if (label < 0 || candidate_of[label] >= 0) continue;
      const float z = cloud_C.points_C[i].z(), z_above = cloud_C.points_C[i - width].z();
      if (std::abs(z_above - z) > config.segmenter.depth_jump_ratio * z) continue;
      if (segmentation.segment_is_plane[label]) {
        // The plane it stands on, seen just behind its top, is no attachment.
        const std::optional<PlaneFit>& plane = up_facing_plane(label);
        if (plane &&
            static_cast<float>(candidate.up.dot(plane->centre)) - candidate.support_height <=
                unknown.min_height_m) {
          continue;
        }
      }
      ++attached;
    }
    return attached * 3 <= top_edge;
  };
  // Until nothing changes: a part is free only through parts that are free themselves.
  std::vector<bool> attached(candidates.size(), false);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (attached[c] || free_at_top(candidates[c])) continue;
      attached[c] = true;
      candidate_of[candidates[c].segment] = -1;
      changed = true;
    }
  }

  // Candidates that meet in the image with continuous depth are parts of one thing (the seat,
  // back and legs of a chair nobody named): one observation, not one per part.
  std::vector<int> group(candidates.size());
  std::iota(group.begin(), group.end(), 0);
  std::function<int(int)> root = [&](int c) {
    return group[c] == c ? c : group[c] = root(group[c]);
  };
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      const int a = segmentation.labels[i];
      if (a < 0 || candidate_of[a] < 0 || !cloud_C.IsValid(i)) continue;
      for (const int j : {u + 1 < width ? i + 1 : -1, v + 1 < height ? i + width : -1}) {
        if (j < 0) continue;
        const int b = segmentation.labels[j];
        if (b < 0 || b == a || candidate_of[b] < 0 || !cloud_C.IsValid(j)) continue;
        const float z_a = cloud_C.points_C[i].z(), z_b = cloud_C.points_C[j].z();
        if (std::abs(z_a - z_b) > config.segmenter.depth_jump_ratio * std::min(z_a, z_b)) continue;
        group[root(candidate_of[a])] = root(candidate_of[b]);
      }
    }
  }
  std::map<int, std::vector<int>> members;  // root -> candidates, ascending
  for (int c = 0; c < static_cast<int>(candidates.size()); ++c) {
    if (!attached[c]) members[root(c)].push_back(c);
  }

  std::vector<float> xs, ys, zs;
  for (const auto& [group_root, parts] : members) {
    std::vector<int> pixels;
    BoundingBox2D box{static_cast<float>(width), static_cast<float>(height), 0.f, 0.f};
    for (int c : parts) {
      const int s = candidates[c].segment;
      pixels.insert(pixels.end(), index.pixel_ids.begin() + index.offsets[s],
                    index.pixel_ids.begin() + index.offsets[s + 1]);
      const SegmentIndex::Segment& segment = index.segments[s];
      box.x_min = std::min(box.x_min, static_cast<float>(segment.u_min));
      box.y_min = std::min(box.y_min, static_cast<float>(segment.v_min));
      box.x_max = std::max(box.x_max, static_cast<float>(segment.u_max));
      box.y_max = std::max(box.y_max, static_cast<float>(segment.v_max));
    }
    std::sort(pixels.begin(), pixels.end());
    const Candidate& first = candidates[parts.front()];
    heights.clear();
    xs.clear();
    ys.clear();
    zs.clear();
    for (int i : pixels) {
      if (!cloud_C.IsValid(i)) continue;
      const Eigen::Vector3f& p = cloud_C.points_C[i];
      heights.push_back(static_cast<float>(first.up.dot(p.cast<double>())) - first.support_height);
      xs.push_back(p.x());
      ys.push_back(p.y());
      zs.push_back(p.z());
    }
    const float rise = Quantile(&heights, kHighQuantile) - Quantile(&heights, kLowQuantile);
    const Eigen::Vector3f extent(Quantile(&xs, kHighQuantile) - Quantile(&xs, kLowQuantile),
                                 Quantile(&ys, kHighQuantile) - Quantile(&ys, kLowQuantile),
                                 Quantile(&zs, kHighQuantile) - Quantile(&zs, kLowQuantile));
    const float size = std::max(extent.maxCoeff(), rise);
    if (size < unknown.min_extent_m || size > unknown.max_extent_m) continue;
    SegmentedDetection entry;
    SetSegment(cloud_C, depth_mm, frame.intrinsics, pixels, config.objects.model_voxel_size_m,
               &entry.observation);
    if (static_cast<int>(entry.observation.segment_C.size()) < config.min_segment_points) continue;
    entry.observation.keyframe_id = keyframe_id;
    entry.observation.box = {box.x_min * sx, box.y_min * sy, (box.x_max + 1.f) * sx,
                             (box.y_max + 1.f) * sy};
    entry.observation.class_scores = {{kUnknownClassId, 0.f}};
    entry.pixels = std::move(pixels);
    result.push_back(std::move(entry));
  }
  return result;
}

}  // namespace objmap
