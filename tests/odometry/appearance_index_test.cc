// AppearanceIndex on random binary descriptors: a keyframe seen again (its descriptors with a
// share of their bits flipped, as ORB gives for the same points from another view) ranks first
// among many; keyframes past max_id are left out; the ranking is reproducible.

#include "odometry/appearance_index.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace objmap {
namespace {

constexpr int kBytes = 32;
constexpr int kDescriptors = 300;

std::vector<std::uint8_t> RandomDescriptors(std::mt19937* random) {
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> descriptors(static_cast<std::size_t>(kDescriptors) * kBytes);
  for (std::uint8_t& b : descriptors) b = static_cast<std::uint8_t>(byte(*random));
  return descriptors;
}

// Each bit flipped with probability `fraction`; only the first `kept` descriptors, the others
// replaced by new ones (points not seen again).
std::vector<std::uint8_t> SeenAgain(const std::vector<std::uint8_t>& descriptors, double fraction,
                                    int kept, std::mt19937* random) {
  std::vector<std::uint8_t> again = RandomDescriptors(random);
  std::bernoulli_distribution flip(fraction);
  for (std::size_t i = 0; i < static_cast<std::size_t>(kept) * kBytes; ++i) {
    std::uint8_t b = descriptors[i];
    for (int bit = 0; bit < 8; ++bit) {
      if (flip(*random)) b = static_cast<std::uint8_t>(b ^ (1u << bit));
    }
    again[i] = b;
  }
  return again;
}

TEST(AppearanceIndex, AKeyframeSeenAgainRanksFirstAmongMany) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 random(seed);
    AppearanceIndex index;
    std::vector<std::vector<std::uint8_t>> keyframes;
    for (int k = 0; k < 400; ++k) {
      keyframes.push_back(RandomDescriptors(&random));
      index.Add(k, keyframes.back().data(), kDescriptors);
    }
    EXPECT_EQ(index.size(), 400);
    // Keyframe 137 again: 40 % of its points, 12 % of their bits changed.
    const std::vector<std::uint8_t> query = SeenAgain(keyframes[137], 0.12, 120, &random);
    const auto ranked = index.MostAlike(query.data(), kDescriptors, 399, 10);
    ASSERT_FALSE(ranked.empty());
    EXPECT_EQ(ranked[0].second, 137) << "seed " << seed;
    ASSERT_GE(ranked.size(), 2u);
    EXPECT_GT(ranked[0].first, 2 * ranked[1].first) << "seed " << seed;
    EXPECT_LE(ranked.size(), 10u);
    // Only keyframes up to max_id are candidates.
    for (const auto& [votes, id] : index.MostAlike(query.data(), kDescriptors, 100, 10)) {
      EXPECT_LE(id, 100);
    }
  }
}

TEST(AppearanceIndex, TheSameSeedGivesTheSameRanking) {
  std::mt19937 random(9);
  std::vector<std::vector<std::uint8_t>> keyframes;
  for (int k = 0; k < 50; ++k) keyframes.push_back(RandomDescriptors(&random));
  const std::vector<std::uint8_t> query = SeenAgain(keyframes[20], 0.15, 100, &random);
  AppearanceIndex a, b;
  for (int k = 0; k < 50; ++k) {
    a.Add(k, keyframes[static_cast<std::size_t>(k)].data(), kDescriptors);
    b.Add(k, keyframes[static_cast<std::size_t>(k)].data(), kDescriptors);
  }
  EXPECT_EQ(a.MostAlike(query.data(), kDescriptors, 49, 20),
            b.MostAlike(query.data(), kDescriptors, 49, 20));
}

TEST(AppearanceIndex, ConfigIsValidated) {
  std::string why;
  EXPECT_TRUE(AppearanceIndexConfig{}.IsValid(&why)) << why;
  AppearanceIndexConfig config;
  config.bits_per_key = 33;
  EXPECT_FALSE(config.IsValid(&why));
  config = {};
  config.tables = 0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("appearance index"), std::string::npos) << why;
}

}  // namespace
}  // namespace objmap
