// RoundNonNegative against std::lround over the range it promises, densest where rounding could
// go wrong: next to every half-integer and just under 0.5.
#include "types/rounding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace objmap {
namespace {

template <typename Real>
int CountMismatchesNearHalves(Real limit, Real step) {
  int mismatches = 0;
  for (Real n = 0; n < limit; n += step) {
    Real x = n + Real(0.5);
    for (int k = 0; k < 4; ++k) x = std::nextafter(x, Real(0));
    for (int k = 0; k < 8; ++k, x = std::nextafter(x, limit)) {
      mismatches += RoundNonNegative(x) == std::lround(x) ? 0 : 1;
    }
  }
  return mismatches;
}

TEST(RoundNonNegativeTest, MatchesLroundNextToHalfIntegers) {
  EXPECT_EQ(CountMismatchesNearHalves<float>(70000.f, 1.f), 0);      // depth in mm
  EXPECT_EQ(CountMismatchesNearHalves<float>(8388000.f, 997.f), 0);  // up to 2^23
  EXPECT_EQ(CountMismatchesNearHalves<double>(256.0, 1.0), 0);       // colour channels
  EXPECT_EQ(CountMismatchesNearHalves<double>(8388000.0, 997.0), 0);
}

TEST(RoundNonNegativeTest, MatchesLroundBelowOneAndAtRandom) {
  int mismatches = 0;
  for (float x = 0.f; x < 1.f; x = std::nextafter(x, 2.f)) {
    mismatches += RoundNonNegative(x) == std::lround(x) ? 0 : 1;
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(RoundNonNegative(std::nextafter(0.5f, 0.f)), 0);  // where x + 0.5f would round up
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0.0, 8388607.0);
  for (int k = 0; k < 1000000; ++k) {
    const double x = value(rng);
    mismatches += RoundNonNegative(x) == std::lround(x) ? 0 : 1;
    mismatches +=
        RoundNonNegative(static_cast<float>(x)) == std::lround(static_cast<float>(x)) ? 0 : 1;
  }
  EXPECT_EQ(mismatches, 0);
}

}  // namespace
}  // namespace objmap
