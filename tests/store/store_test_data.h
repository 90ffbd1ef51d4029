#pragma once
// Deterministic keyframes and observations for the store tests, and comparisons of what comes
// back from the store with what went in.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "store/keyframe_store.h"

namespace objmap {
namespace testing {

/// A scratch folder per test case (pid + name: parallel ctest runs do not collide).
class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("objmap_store_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Path(const std::string& name = "map.db") const { return (dir_ / name).string(); }

  std::unique_ptr<KeyframeStore> OpenStore(const std::string& path) const {
    std::string why;
    auto store = KeyframeStore::Open(path, KeyframeStoreConfig{}, &why);
    EXPECT_NE(store, nullptr) << why;
    return store;
  }

  std::filesystem::path dir_;
};

/// A keyframe whose every field depends on `id`: depth covers 0 (no depth) and large values,
/// the pose has digits a float would lose, colour is a smooth gradient (JPEG keeps it close).
inline StoredKeyframe MakeKeyframe(KeyframeId id, bool with_color = true, int width = 64,
                                   int height = 48) {
  StoredKeyframe k;
  k.id = id;
  k.stamp_s = 1000.0 + id / 3.0;
  k.name = "frame-" + std::to_string(id);
  k.T_W_C = Eigen::Translation3d(id * 0.1234567890123, 0.5 / 3.0, -1.0 / 7.0) *
            Eigen::AngleAxisd(0.1 * id + 1e-12, Eigen::Vector3d(1, 2, 3).normalized());
  k.intrinsics.width = width;
  k.intrinsics.height = height;
  k.intrinsics.fx = 525.5 + id;
  k.intrinsics.fy = 524.25;
  k.intrinsics.cx = width / 2.0 - 0.5;
  k.intrinsics.cy = height / 2.0 + 0.25;
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  k.depth_mm.resize(pixels);
  k.object_mask.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    k.depth_mm[i] = i % 11 == 0 ? 0 : static_cast<std::uint16_t>((id * 7919 + i * 37) % 65536);
    k.object_mask[i] = (i + id) % 3 == 0 ? 1 : 0;
  }
  if (with_color) {
    k.color.width = width;
    k.color.height = height;
    k.color.rgb.resize(3 * pixels);
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        std::uint8_t* p = &k.color.rgb[3 * (static_cast<std::size_t>(v) * width + u)];
        p[0] = static_cast<std::uint8_t>(2 * u + id);
        p[1] = static_cast<std::uint8_t>(3 * v);
        p[2] = static_cast<std::uint8_t>(100 + u + v);
      }
    }
  }
  k.detections = {{{1.5f, 2.25f, 30.f, 40.125f}, 41, 0.875f},
                  {{0.f, 0.f, 10.f, 12.f}, static_cast<int>(id % 80), 0.3f}};
  return k;
}

/// An observation of `object` in `keyframe` with `points` points (coloured or not).
inline StoredObservation MakeObservation(ObjectId object, KeyframeId keyframe, int points,
                                         bool colored = true) {
  StoredObservation o;
  o.object_id = object;
  o.observation.keyframe_id = keyframe;
  o.observation.box = {1.f * object, 2.f * keyframe, 10.5f + object, 20.25f + keyframe};
  o.observation.class_scores = {{static_cast<int>(object % 80), 0.625f}, {41, 0.1f / 3}};
  for (int i = 0; i < points; ++i) {
    o.observation.segment_C.points.emplace_back(0.001f * i, -0.1f * object, 1.f / (i + 1));
    if (colored) {
      o.observation.segment_C.colors.push_back({static_cast<std::uint8_t>(i),
                                                static_cast<std::uint8_t>(object),
                                                static_cast<std::uint8_t>(keyframe)});
    }
  }
  return o;
}

/// An observation of `object` made from `keyframe`'s depth as the mapper makes it
/// (SegmentPointsFromDepth): the pixels of the rectangle [u0, u1) x [v0, v1) and every 7th
/// pixel of the row below it, coloured from the keyframe's colour when it has one.
inline StoredObservation MakeObservationOfPixels(ObjectId object, const StoredKeyframe& keyframe,
                                                 int u0, int u1, int v0, int v1,
                                                 float voxel_size_m = 0.005f) {
  const int width = keyframe.intrinsics.width;
  std::vector<int> pixels;
  for (int v = v0; v < v1; ++v) {
    for (int u = u0; u < u1; ++u) pixels.push_back(v * width + u);
  }
  for (int u = 0; u < width; u += 7) pixels.push_back(v1 * width + u);
  std::vector<std::array<std::uint8_t, 3>> rgb;
  for (std::size_t i = 0; i + 2 < keyframe.color.rgb.size(); i += 3) {
    rgb.push_back({keyframe.color.rgb[i], keyframe.color.rgb[i + 1], keyframe.color.rgb[i + 2]});
  }
  StoredObservation o;
  o.object_id = object;
  o.observation.keyframe_id = keyframe.id;
  o.observation.box = {1.f * u0, 1.f * v0, 1.f * u1, 1.f * v1};
  o.observation.class_scores = {{static_cast<int>(object % 80), 0.5f}};
  o.observation.segment_pixels = RunsOf(pixels);
  o.observation.segment_voxel_size_m = voxel_size_m;
  o.observation.segment_C =
      SegmentPointsFromDepth(keyframe.depth_mm, keyframe.intrinsics, o.observation.segment_pixels,
                             voxel_size_m, rgb.empty() ? nullptr : &rgb);
  return o;
}

/// Everything exact except colour, which may differ by `color_tolerance` on average (JPEG).
inline void ExpectSameKeyframe(const StoredKeyframe& expected, const StoredKeyframe& actual,
                               double color_tolerance) {
  SCOPED_TRACE("keyframe " + std::to_string(expected.id));
  EXPECT_EQ(actual.id, expected.id);
  EXPECT_EQ(actual.stamp_s, expected.stamp_s);
  EXPECT_EQ(actual.name, expected.name);
  EXPECT_EQ(actual.session_id, expected.session_id);
  EXPECT_EQ(actual.T_W_C.matrix(), expected.T_W_C.matrix());  // bit-exact doubles
  EXPECT_EQ(actual.intrinsics.width, expected.intrinsics.width);
  EXPECT_EQ(actual.intrinsics.height, expected.intrinsics.height);
  EXPECT_EQ(actual.intrinsics.fx, expected.intrinsics.fx);
  EXPECT_EQ(actual.intrinsics.fy, expected.intrinsics.fy);
  EXPECT_EQ(actual.intrinsics.cx, expected.intrinsics.cx);
  EXPECT_EQ(actual.intrinsics.cy, expected.intrinsics.cy);
  EXPECT_EQ(actual.depth_mm, expected.depth_mm);
  EXPECT_EQ(actual.object_mask, expected.object_mask);
  ASSERT_EQ(actual.detections.size(), expected.detections.size());
  for (std::size_t i = 0; i < expected.detections.size(); ++i) {
    const Detection &a = actual.detections[i], &e = expected.detections[i];
    EXPECT_EQ(a.class_id, e.class_id);
    EXPECT_EQ(a.score, e.score);
    EXPECT_EQ(a.box.x_min, e.box.x_min);
    EXPECT_EQ(a.box.y_min, e.box.y_min);
    EXPECT_EQ(a.box.x_max, e.box.x_max);
    EXPECT_EQ(a.box.y_max, e.box.y_max);
  }
  ASSERT_EQ(actual.color.empty(), expected.color.empty());
  if (expected.color.empty()) return;
  EXPECT_EQ(actual.color.width, expected.color.width);
  EXPECT_EQ(actual.color.height, expected.color.height);
  ASSERT_EQ(actual.color.rgb.size(), expected.color.rgb.size());
  double difference = 0.0;
  for (std::size_t i = 0; i < expected.color.rgb.size(); ++i) {
    difference += std::abs(int{actual.color.rgb[i]} - int{expected.color.rgb[i]});
  }
  EXPECT_LE(difference / expected.color.rgb.size(), color_tolerance);
}

inline void ExpectSameObservation(const StoredObservation& expected,
                                  const StoredObservation& actual) {
  const ObjectObservation &e = expected.observation, &a = actual.observation;
  SCOPED_TRACE("observation of object " + std::to_string(expected.object_id) + " in keyframe " +
               std::to_string(e.keyframe_id));
  EXPECT_EQ(actual.object_id, expected.object_id);
  EXPECT_EQ(a.keyframe_id, e.keyframe_id);
  EXPECT_EQ(a.box.x_min, e.box.x_min);
  EXPECT_EQ(a.box.y_min, e.box.y_min);
  EXPECT_EQ(a.box.x_max, e.box.x_max);
  EXPECT_EQ(a.box.y_max, e.box.y_max);
  EXPECT_EQ(a.class_scores, e.class_scores);
  EXPECT_EQ(a.segment_C.points, e.segment_C.points);
  EXPECT_EQ(a.segment_C.colors, e.segment_C.colors);
  EXPECT_EQ(a.segment_pixels, e.segment_pixels);
  EXPECT_EQ(a.segment_voxel_size_m, e.segment_voxel_size_m);
}

/// Two loads of the same database: identical, colour included.
inline void ExpectSameMap(const StoredMap& expected, const StoredMap& actual) {
  EXPECT_EQ(actual.map_version, expected.map_version);
  EXPECT_EQ(actual.next_object_id, expected.next_object_id);
  ASSERT_EQ(actual.keyframes.size(), expected.keyframes.size());
  for (std::size_t i = 0; i < expected.keyframes.size(); ++i) {
    ExpectSameKeyframe(expected.keyframes[i], actual.keyframes[i], 0.0);
    EXPECT_EQ(actual.keyframes[i].color.rgb, expected.keyframes[i].color.rgb);
  }
  ASSERT_EQ(actual.observations.size(), expected.observations.size());
  for (std::size_t i = 0; i < expected.observations.size(); ++i) {
    ExpectSameObservation(expected.observations[i], actual.observations[i]);
  }
  ASSERT_EQ(actual.objects.size(), expected.objects.size());
  for (std::size_t i = 0; i < expected.objects.size(); ++i) {
    EXPECT_EQ(actual.objects[i].id, expected.objects[i].id);
    EXPECT_EQ(actual.objects[i].class_id, expected.objects[i].class_id);
    EXPECT_EQ(actual.objects[i].confidence, expected.objects[i].confidence);
    EXPECT_EQ(actual.objects[i].centroid_W, expected.objects[i].centroid_W);
    EXPECT_EQ(actual.objects[i].observations, expected.objects[i].observations);
  }
}

}  // namespace testing
}  // namespace objmap
