#include "odometry/appearance_index.h"

#include <algorithm>
#include <random>

namespace objmap {

bool AppearanceIndexConfig::IsValid(std::string* why) const {
  if (tables < 1 || bits_per_key < 1 || bits_per_key > 32 || descriptor_bytes < 1 ||
      bits_per_key > 8 * descriptor_bytes) {
    *why =
        "appearance index: tables >= 1, bits_per_key in [1, 32] and at most the descriptor's "
        "bits, descriptor_bytes >= 1";
    return false;
  }
  return true;
}

AppearanceIndex::AppearanceIndex(const AppearanceIndexConfig& config)
    : config_(config), buckets_(static_cast<std::size_t>(config.tables)) {
  std::mt19937_64 random(config.seed);
  std::vector<int> positions(static_cast<std::size_t>(8 * config.descriptor_bytes));
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = static_cast<int>(i);
  for (int t = 0; t < config.tables; ++t) {
    std::shuffle(positions.begin(), positions.end(), random);
    bits_.emplace_back(positions.begin(), positions.begin() + config.bits_per_key);
  }
}

std::uint32_t AppearanceIndex::Key(int table, const std::uint8_t* descriptor) const {
  std::uint32_t key = 0;
  for (const int bit : bits_[static_cast<std::size_t>(table)]) {
    key = (key << 1) | ((descriptor[bit >> 3] >> (bit & 7)) & 1u);
  }
  return key;
}

void AppearanceIndex::Add(int id, const std::uint8_t* descriptors, int rows) {
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* descriptor = descriptors + static_cast<std::size_t>(r) * config_.descriptor_bytes;
    for (int t = 0; t < config_.tables; ++t) {
      std::vector<int>& bucket = buckets_[static_cast<std::size_t>(t)][Key(t, descriptor)];
      // One entry per keyframe and bucket: a keyframe's repeated texture votes once.
      if (bucket.empty() || bucket.back() != id) bucket.push_back(id);
    }
  }
  ++keyframes_;
}

std::vector<std::pair<int, int>> AppearanceIndex::MostAlike(const std::uint8_t* descriptors,
                                                            int rows, int max_id,
                                                            int count) const {
  std::unordered_map<int, int> votes;
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* descriptor = descriptors + static_cast<std::size_t>(r) * config_.descriptor_bytes;
    for (int t = 0; t < config_.tables; ++t) {
      const auto& table = buckets_[static_cast<std::size_t>(t)];
      const auto bucket = table.find(Key(t, descriptor));
      if (bucket == table.end()) continue;
      for (const int id : bucket->second) {
        if (id <= max_id) ++votes[id];
      }
    }
  }
  std::vector<std::pair<int, int>> ranked;
  ranked.reserve(votes.size());
  for (const auto& [id, n] : votes) ranked.emplace_back(n, id);
  // Most votes first; among equals the older keyframe, so that the order does not depend on
  // the hash map's.
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  if (static_cast<int>(ranked.size()) > count) ranked.resize(static_cast<std::size_t>(count));
  return ranked;
}

}  // namespace objmap
