#include "association/proximity_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "objects/voxel_model.h"
#include "test_scenes.h"

namespace objmap {
namespace {

// The reference: every model point tried, squared distance summed as a nearest-neighbour search
// sums it.
bool BruteForceWithin(const std::vector<Eigen::Vector3f>& model_points, const Eigen::Vector3f& p,
                      float radius_m) {
  for (const Eigen::Vector3f& q : model_points) {
    const float dx = p.x() - q.x(), dy = p.y() - q.y(), dz = p.z() - q.z();
    float distance_sq = dx * dx;
    distance_sq += dy * dy;
    distance_sq += dz * dz;
    if (distance_sq <= radius_m * radius_m) return true;
  }
  return false;
}

VoxelModel ModelOf(const std::vector<Eigen::Vector3f>& points) {
  VoxelModel model;
  model.Insert(ColoredPoints{points, {}});
  return model;
}

std::vector<Eigen::Vector3f> UniformPoints(std::mt19937* rng, std::size_t n,
                                           const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f t(unit(*rng), unit(*rng), unit(*rng));
    points.push_back(lo + t.cwiseProduct(hi - lo));
  }
  return points;
}

// Counts disagreements of the grid with the brute force over `queries`; also counts matches so
// that a test can check it covered both answers.
struct Agreement {
  int disagreements = 0;
  int matches = 0;
};

Agreement Compare(const VoxelModel& model, float radius_m,
                  const std::vector<Eigen::Vector3f>& queries) {
  const std::vector<Eigen::Vector3f> model_points = model.Points().points;
  const ProximityGrid grid(model_points, radius_m);
  Agreement agreement;
  for (const Eigen::Vector3f& p : queries) {
    const bool expected = BruteForceWithin(model_points, p, radius_m);
    agreement.matches += expected ? 1 : 0;
    if (grid.AnyWithin(p) != expected) ++agreement.disagreements;
  }
  return agreement;
}

TEST(ProximityGrid, AgreesWithBruteForceOnRandomClouds) {
  std::mt19937 rng(7);
  for (const float radius_m : {0.02f, 0.05f, 0.013f}) {
    // Sparse and dense clouds, around the origin and far from it (negative cells included).
    for (const Eigen::Vector3f& offset :
         {Eigen::Vector3f(-0.1f, -0.1f, -0.1f), Eigen::Vector3f(-12.3f, 4.56f, -7.f)}) {
      for (const std::size_t n : {5u, 300u, 3000u}) {
        const auto model_points =
            UniformPoints(&rng, n, offset, offset + Eigen::Vector3f(0.3f, 0.2f, 0.25f));
        auto queries = UniformPoints(&rng, 4000, offset - Eigen::Vector3f::Constant(0.1f),
                                     offset + Eigen::Vector3f(0.4f, 0.3f, 0.35f));
        // Queries around the model points too, so that sparse models see matches and misses.
        for (const Eigen::Vector3f& q : model_points) {
          for (const Eigen::Vector3f& jitter :
               UniformPoints(&rng, 20, Eigen::Vector3f::Constant(-1.5f * radius_m),
                             Eigen::Vector3f::Constant(1.5f * radius_m))) {
            queries.push_back(q + jitter);
          }
        }
        const Agreement agreement = Compare(ModelOf(model_points), radius_m, queries);
        EXPECT_EQ(agreement.disagreements, 0) << "radius " << radius_m << ", " << n << " points";
        EXPECT_GT(agreement.matches, 0);
        EXPECT_LT(agreement.matches, static_cast<int>(queries.size()));
      }
    }
  }
}

TEST(ProximityGrid, AgreesWithBruteForceOnSurfaces) {
  const auto box = testing::BoxSurface({0.1f, -0.2f, 0.5f}, {0.5f, 0.1f, 0.8f}, 0.005f);
  const VoxelModel model = ModelOf(box);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 0.015f);
  std::vector<Eigen::Vector3f> queries;
  for (const Eigen::Vector3f& p : box) {
    queries.push_back(p + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  }
  for (const float radius_m : {0.02f, 0.05f}) {
    const Agreement agreement = Compare(model, radius_m, queries);
    EXPECT_EQ(agreement.disagreements, 0) << "radius " << radius_m;
    EXPECT_GT(agreement.matches, 0);
  }
}

// Queries whose distance to the nearest model point is the radius give or take a few float
// steps, along axes and diagonals, at cell borders (coordinates that are multiples of the radius)
// and away from them: the grid must not lose a match at the border nor invent one.
TEST(ProximityGrid, PointsAtTheRadiusAgreeWithBruteForce) {
  const float radius_m = 0.02f;
  const std::vector<Eigen::Vector3f> model_points = {
      {0.f, 0.f, 0.f}, {0.04f, 0.04f, 0.04f}, {-0.06f, 0.02f, 0.1f}, {1.0037f, -2.0011f, 0.5f}};
  const VoxelModel model = ModelOf(model_points);
  std::vector<Eigen::Vector3f> queries;
  const std::vector<Eigen::Vector3f> directions = {
      {1, 0, 0},
      {-1, 0, 0},
      {0, 1, 0},
      {0, 0, -1},
      Eigen::Vector3f(1, 1, 0).normalized(),
      Eigen::Vector3f(1, -1, 1).normalized(),
      Eigen::Vector3f(-0.3f, 0.5f, -0.8f).normalized()};
  for (const Eigen::Vector3f& q : model.Points().points) {
    for (const Eigen::Vector3f& d : directions) {
      const Eigen::Vector3f at_radius = q + radius_m * d;
      for (int step = -3; step <= 3; ++step) {
        Eigen::Vector3f p = at_radius;
        for (int axis = 0; axis < 3; ++axis) {
          for (int s = 0; s < std::abs(step); ++s) {
            const float away = d[axis] >= 0.f ? 1.f : -1.f;
            p[axis] = std::nextafter(p[axis], (step > 0 ? away : -away) * 1e9f);
          }
        }
        queries.push_back(p);
      }
    }
  }
  const Agreement agreement = Compare(model, radius_m, queries);
  EXPECT_EQ(agreement.disagreements, 0);
  EXPECT_GT(agreement.matches, 0);
  EXPECT_LT(agreement.matches, static_cast<int>(queries.size()));
}

TEST(ProximityGrid, EmptyModelMatchesNothing) {
  const ProximityGrid grid({}, 0.02f);
  EXPECT_TRUE(grid.empty());
  EXPECT_FALSE(grid.AnyWithin(Eigen::Vector3f::Zero()));
  EXPECT_FALSE(grid.AnyWithin(Eigen::Vector3f(1.f, 2.f, 3.f)));
}

TEST(ProximityGrid, NonFiniteQueriesMatchNothing) {
  const ProximityGrid grid({{0.f, 0.f, 0.f}}, 0.02f);
  EXPECT_TRUE(grid.AnyWithin(Eigen::Vector3f(0.01f, 0.f, 0.f)));
  EXPECT_FALSE(grid.AnyWithin(Eigen::Vector3f(std::nanf(""), 0.f, 0.f)));
  EXPECT_FALSE(grid.AnyWithin(Eigen::Vector3f(0.f, INFINITY, 0.f)));
}

}  // namespace
}  // namespace objmap
