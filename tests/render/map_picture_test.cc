// Pictures of a small synthetic map: a floor, two cups and a screen. Each object's class colour
// must show where its centroid projects, the legend must count what is drawn, and the filters
// and bad input must do what they say.
#include "render/map_picture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <set>

namespace objmap {
namespace {

// A solid box of points on a grid: whatever side a view sees, it sees the object.
std::vector<Eigen::Vector3f> SolidBox(const Eigen::Vector3f& low, const Eigen::Vector3f& high,
                                      float step) {
  std::vector<Eigen::Vector3f> points;
  for (float x = low.x(); x <= high.x() + 1e-6f; x += step) {
    for (float y = low.y(); y <= high.y() + 1e-6f; y += step) {
      for (float z = low.z(); z <= high.z() + 1e-6f; z += step) points.emplace_back(x, y, z);
    }
  }
  return points;
}

PictureObject Object(ObjectId id, const std::string& name, const Eigen::Vector3f& low,
                     const Eigen::Vector3f& high) {
  PictureObject object;
  object.id = id;
  object.class_name = name;
  object.confidence = 0.5f;
  object.points_W = SolidBox(low, high, 0.005f);
  return object;
}

Eigen::Vector3d Centroid(const PictureObject& object) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : object.points_W) sum += p.cast<double>();
  return sum / static_cast<double>(object.points_W.size());
}

// A 3 x 2 m floor (z = 0, up +z), a cup on each side, a screen standing at the back.
PictureScene Scene() {
  PictureScene scene;
  for (float x = -1.5f; x <= 1.5f; x += 0.01f) {
    for (float y = -1.f; y <= 1.f; y += 0.01f) scene.structure_W.emplace_back(x, y, 0.f);
  }
  scene.objects.push_back(Object(1, "cup", {-1.0f, -0.5f, 0.01f}, {-0.9f, -0.4f, 0.12f}));
  scene.objects.push_back(Object(2, "cup", {0.9f, -0.5f, 0.01f}, {1.0f, -0.4f, 0.12f}));
  scene.objects.push_back(Object(3, "tv", {-0.3f, 0.6f, 0.01f}, {0.3f, 0.65f, 0.4f}));
  return scene;
}

RgbColour PixelAt(const MapPicture& picture, const Eigen::Vector2d& uv) {
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  EXPECT_TRUE(u >= 0 && v >= 0 && u < picture.width && v < picture.height) << uv.transpose();
  const std::size_t i = 3 * (static_cast<std::size_t>(std::clamp(v, 0, picture.height - 1)) *
                                 picture.width +
                             std::clamp(u, 0, picture.width - 1));
  return {picture.rgb[i], picture.rgb[i + 1], picture.rgb[i + 2]};
}

bool Near(const RgbColour& a, const RgbColour& b, int tolerance) {
  for (int c = 0; c < 3; ++c) {
    if (std::abs(static_cast<int>(a[c]) - static_cast<int>(b[c])) > tolerance) return false;
  }
  return true;
}

std::string Text(const RgbColour& c) {
  return std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]);
}

void ExpectClassColoursAtCentroids(const PictureScene& scene, const MapPicture& picture) {
  for (const PictureObject& object : scene.objects) {
    const auto uv = picture.camera.Project(Centroid(object));
    ASSERT_TRUE(uv.has_value()) << object.class_name;
    const RgbColour seen = PixelAt(picture, *uv);
    EXPECT_TRUE(Near(seen, ClassColour(object.class_name), 12))
        << object.class_name << " #" << object.id << ": " << Text(seen) << " at " << uv->transpose()
        << ", class colour " << Text(ClassColour(object.class_name));
  }
}

TEST(MapPicture, EachObjectShowsItsClassColourAtItsCentroidInEveryView) {
  const PictureScene scene = Scene();
  for (const PictureView view : {PictureView::kTop, PictureView::kPerspective}) {
    PictureConfig config;
    config.view = view;
    MapPicture picture;
    std::string why;
    ASSERT_TRUE(RenderMapPicture(scene, config, &picture, &why)) << why;
    ASSERT_EQ(picture.rgb.size(), 3u * 1280u * 960u);
    SCOPED_TRACE(PictureViewName(view));
    ExpectClassColoursAtCentroids(scene, picture);
    // Not blank, not uniform: background, greys, three class colours, text.
    std::set<int> colours;
    for (std::size_t i = 0; i < picture.rgb.size(); i += 3) {
      colours.insert(picture.rgb[i] << 16 | picture.rgb[i + 1] << 8 | picture.rgb[i + 2]);
    }
    EXPECT_GT(colours.size(), 20u);
    ASSERT_EQ(picture.legend.size(), 2u);
    EXPECT_EQ(picture.legend[0].class_name, "cup");
    EXPECT_EQ(picture.legend[0].count, 2);
    EXPECT_EQ(picture.legend[1].class_name, "tv");
    EXPECT_EQ(picture.legend[1].count, 1);
    EXPECT_GT(picture.scale_bar_m, 0.0);
    EXPECT_GT(picture.scale_bar_px, 4);
  }
}

TEST(MapPicture, TheTopViewLooksDownTheUpDirectionAndItsScaleBarMeasuresTheFloor) {
  PictureScene scene = Scene();
  PictureConfig config;
  config.view = PictureView::kTop;
  MapPicture picture;
  std::string why;
  ASSERT_TRUE(RenderMapPicture(scene, config, &picture, &why)) << why;
  EXPECT_LT((picture.camera.T_W_C.linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);
  // Two floor points scale_bar_m apart are scale_bar_px apart in the picture (within 2 %: the
  // bar is measured at the view's centre, the floor lies a little below it).
  const auto a = picture.camera.Project({0.0, 0.0, 0.0});
  const auto b = picture.camera.Project({picture.scale_bar_m, 0.0, 0.0});
  ASSERT_TRUE(a && b);
  EXPECT_NEAR((*b - *a).norm(), picture.scale_bar_px, 0.05 * picture.scale_bar_px);
  // The floor's long side (3 m along x) runs along the picture's width.
  const auto left = picture.camera.Project({-1.5, 0.0, 0.0});
  const auto right = picture.camera.Project({1.5, 0.0, 0.0});
  ASSERT_TRUE(left && right);
  EXPECT_GT(std::abs(right->x() - left->x()), 0.6 * picture.width);
}

TEST(MapPicture, AClassOrARegionFocusesThePicture) {
  const PictureScene scene = Scene();
  PictureConfig config;
  config.view = PictureView::kTop;
  config.only_class = "tv";
  MapPicture picture;
  std::string why;
  ASSERT_TRUE(RenderMapPicture(scene, config, &picture, &why)) << why;
  ASSERT_EQ(picture.legend.size(), 1u);
  EXPECT_EQ(picture.legend[0].class_name, "tv");
  const auto tv = picture.camera.Project(Centroid(scene.objects[2]));
  ASSERT_TRUE(tv);
  EXPECT_TRUE(Near(PixelAt(picture, *tv), ClassColour("tv"), 12));
  // Framed on the 60 cm screen: it spans most of the picture's width.
  const auto left = picture.camera.Project({-0.3, 0.62, 0.4});
  const auto right = picture.camera.Project({0.3, 0.62, 0.4});
  ASSERT_TRUE(left && right);
  EXPECT_GT(std::abs(right->x() - left->x()), 0.5 * picture.width);

  config.only_class.clear();
  config.region = Eigen::AlignedBox3f(Eigen::Vector3f(0.5f, -1.f, -0.1f), Eigen::Vector3f(1.5f, 0.f, 0.5f));
  ASSERT_TRUE(RenderMapPicture(scene, config, &picture, &why)) << why;
  ASSERT_EQ(picture.legend.size(), 1u);
  EXPECT_EQ(picture.legend[0].count, 1);  // the cup inside the box
  const auto inside = picture.camera.Project(Centroid(scene.objects[1]));
  ASSERT_TRUE(inside);
  EXPECT_TRUE(Near(PixelAt(picture, *inside), ClassColour("cup"), 12));
  // The other cup lies outside the box: not drawn, even where it would project into the picture.
  const auto outside = picture.camera.Project(Centroid(scene.objects[0]));
  if (outside && outside->x() >= 0 && outside->y() >= 0 && outside->x() < picture.width &&
      outside->y() < picture.height) {
    EXPECT_FALSE(Near(PixelAt(picture, *outside), ClassColour("cup"), 40));
  }
}

TEST(MapPicture, AGivenCameraSeesWhatItLooksAt) {
  const PictureScene scene = Scene();
  PictureConfig config;
  config.view = PictureView::kCamera;
  // 1 m in front of the second cup, level with it, looking along +y at it... from -y.
  const Eigen::Vector3d cup = Centroid(scene.objects[1]);
  Eigen::Matrix3d R;
  R.col(2) = Eigen::Vector3d(0, 1, 0);   // forward
  R.col(0) = Eigen::Vector3d(1, 0, 0);   // right
  R.col(1) = R.col(2).cross(R.col(0));   // down: -z
  config.T_W_C.linear() = R;
  config.T_W_C.translation() = cup - Eigen::Vector3d(0, 1.0, 0);
  MapPicture picture;
  std::string why;
  ASSERT_TRUE(RenderMapPicture(scene, config, &picture, &why)) << why;
  const auto uv = picture.camera.Project(cup);
  ASSERT_TRUE(uv);
  EXPECT_NEAR(uv->x(), 640.0, 1.0);
  EXPECT_NEAR(uv->y(), 480.0, 1.0);
  EXPECT_TRUE(Near(PixelAt(picture, *uv), ClassColour("cup"), 12)) << Text(PixelAt(picture, *uv));
}

TEST(MapPicture, NothingToShowOrABadConfigIsAClearError) {
  MapPicture picture;
  std::string why;
  EXPECT_FALSE(RenderMapPicture(PictureScene{}, PictureConfig{}, &picture, &why));
  EXPECT_NE(why.find("empty"), std::string::npos) << why;
  PictureConfig config;
  config.only_class = "giraffe";
  EXPECT_FALSE(RenderMapPicture(Scene(), config, &picture, &why));
  EXPECT_NE(why.find("giraffe"), std::string::npos) << why;
  config = PictureConfig{};
  config.region = Eigen::AlignedBox3f(Eigen::Vector3f(10, 10, 10), Eigen::Vector3f(11, 11, 11));
  EXPECT_FALSE(RenderMapPicture(Scene(), config, &picture, &why));
  EXPECT_NE(why.find("region"), std::string::npos) << why;
  config = PictureConfig{};
  config.width = 10;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("wide"), std::string::npos) << why;
  config = PictureConfig{};
  config.up_W = Eigen::Vector3d::Zero();
  EXPECT_FALSE(config.IsValid(&why));
  config = PictureConfig{};
  config.T_W_C.linear() *= 2.0;
  EXPECT_FALSE(config.IsValid(&why));
  PictureView view;
  EXPECT_TRUE(ParsePictureView("top", &view));
  EXPECT_EQ(view, PictureView::kTop);
  EXPECT_FALSE(ParsePictureView("sideways", &view));
}

TEST(MapPicture, WritesAPngOrSaysWhyNot) {
  MapPicture picture;
  std::string why;
  PictureConfig config;
  config.width = 320;
  config.height = 240;
  ASSERT_TRUE(RenderMapPicture(Scene(), config, &picture, &why)) << why;
  const auto path = std::filesystem::temp_directory_path() /
                    ("objmap_picture_" + std::to_string(::getpid()) + ".png");
  ASSERT_TRUE(WritePicturePng(picture, path.string(), &why)) << why;
  const cv::Mat read = cv::imread(path.string());
  std::filesystem::remove(path);
  ASSERT_FALSE(read.empty());
  EXPECT_EQ(read.cols, 320);
  EXPECT_EQ(read.rows, 240);
  EXPECT_FALSE(WritePicturePng(picture, "/nonexistent-folder/x.png", &why));
  EXPECT_NE(why.find("/nonexistent-folder/x.png"), std::string::npos) << why;
  EXPECT_FALSE(WritePicturePng(MapPicture{}, path.string(), &why));
}

TEST(MapPicture, UpComesFromUnrolledCamerasWhateverTheirPitch) {
  // Cameras pitched 30 degrees down at eight headings, in a world whose up is `truth`.
  for (const Eigen::Vector3d& truth : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, -1, 0),
                                      Eigen::Vector3d(0.3, -0.9, 0.3).normalized()}) {
    const Eigen::Quaterniond to_world = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(0, 0, 1), truth);
    std::vector<Eigen::Isometry3d> cameras;
    for (int k = 0; k < 8; ++k) {
      const double heading = k * 0.785;
      const double pitch = -30.0 * 3.14159265 / 180.0;
      // A camera in a z-up world: forward horizontal at `heading`, then pitched down.
      const Eigen::Vector3d forward(std::cos(heading) * std::cos(pitch),
                                    std::sin(heading) * std::cos(pitch), std::sin(pitch));
      const Eigen::Vector3d right = forward.cross(Eigen::Vector3d(0, 0, 1)).normalized();
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear().col(0) = to_world * right;
      T.linear().col(2) = to_world * forward;
      T.linear().col(1) = T.linear().col(2).cross(T.linear().col(0));
      cameras.push_back(T);
    }
    const auto up = UpFromCameras(cameras);
    ASSERT_TRUE(up.has_value());
    EXPECT_GT(up->dot(truth), std::cos(0.5 * 3.14159265 / 180.0)) << up->transpose();
    // All facing one way, a pitch cannot be told from a tilted world: their image-up axis.
    const auto one_way = UpFromCameras({cameras[0], cameras[0]});
    ASSERT_TRUE(one_way.has_value());
    EXPECT_GT(one_way->dot(-cameras[0].linear().col(1)), 0.9999) << one_way->transpose();
  }
  EXPECT_FALSE(UpFromCameras({}).has_value());
}

}  // namespace
}  // namespace objmap
