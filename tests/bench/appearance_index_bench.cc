// AppearanceIndex against matching every keyframe: the time to rank the keyframes that look like
// a new one, as the map grows. Keyframes are 300 random ORB-sized descriptors each; the query is
// one of them seen again (40 % of its descriptors with 12 % of their bits flipped). The brute
// force is what the loop search did before the index: a 2-NN ratio test against each keyframe.
//   appearance_index_bench [keyframes...=100 1000 3000]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "odometry/appearance_index.h"

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kDescriptors = 300;

cv::Mat RandomDescriptors(std::mt19937* random) {
  cv::Mat descriptors(kDescriptors, 32, CV_8U);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int r = 0; r < descriptors.rows; ++r) {
    for (int c = 0; c < 32; ++c) descriptors.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(*random));
  }
  return descriptors;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes;
  for (int i = 1; i < argc; ++i) sizes.push_back(std::atoi(argv[i]));
  if (sizes.empty()) sizes = {100, 1000, 3000};
  std::printf("keyframes | index query ms | found | brute force ms | found | speed-up\n");
  for (const int n : sizes) {
    std::mt19937 random(static_cast<unsigned>(n));
    std::vector<cv::Mat> keyframes;
    objmap::AppearanceIndex index;
    for (int k = 0; k < n; ++k) {
      keyframes.push_back(RandomDescriptors(&random));
      index.Add(k, keyframes.back().ptr<std::uint8_t>(), kDescriptors);
    }
    const int target = n / 3;
    cv::Mat query = RandomDescriptors(&random);
    std::bernoulli_distribution flip(0.12);
    for (int r = 0; r < 120; ++r) {
      for (int c = 0; c < 32; ++c) {
        std::uint8_t b = keyframes[static_cast<std::size_t>(target)].at<std::uint8_t>(r, c);
        for (int bit = 0; bit < 8; ++bit) {
          if (flip(random)) b = static_cast<std::uint8_t>(b ^ (1u << bit));
        }
        query.at<std::uint8_t>(r, c) = b;
      }
    }
    const auto index_start = Clock::now();
    const auto ranked = index.MostAlike(query.ptr<std::uint8_t>(), kDescriptors, n - 1, 10);
    const double index_ms =
        std::chrono::duration<double, std::milli>(Clock::now() - index_start).count();
    const auto brute_start = Clock::now();
    const cv::BFMatcher matcher(cv::NORM_HAMMING);
    int best = -1, best_matches = -1;
    for (int k = 0; k < n; ++k) {
      std::vector<std::vector<cv::DMatch>> knn;
      matcher.knnMatch(query, keyframes[static_cast<std::size_t>(k)], knn, 2);
      int matches = 0;
      for (const auto& pair : knn) matches += pair.size() == 2 && pair[0].distance < 0.8f * pair[1].distance;
      if (matches > best_matches) {
        best_matches = matches;
        best = k;
      }
    }
    const double brute_ms =
        std::chrono::duration<double, std::milli>(Clock::now() - brute_start).count();
    std::printf("%9d | %14.2f | %5s | %14.1f | %5s | %.0fx\n", n, index_ms,
                !ranked.empty() && ranked[0].second == target ? "yes" : "no", brute_ms,
                best == target ? "yes" : "no", brute_ms / std::max(1e-6, index_ms));
  }
  return 0;
}
