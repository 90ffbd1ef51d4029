#pragma once
// Keyframes by appearance: their strongest ORB descriptors hashed on a few bits each into several
// tables (locality-sensitive hashing of binary descriptors). A new keyframe's descriptors vote
// for the keyframes whose descriptors share a bucket with theirs, so the loop search compares it
// with the few keyframes that look most alike instead of with every one: a cost that stays flat
// as the map grows, where matching against each keyframe grows with it.

#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace objmap {

struct AppearanceIndexConfig {
  /// Hash tables, each keyed on its own bits_per_key bit positions of the descriptor. Two
  /// descriptors of one point differ in about 10-15 % of their bits: they share a key with
  /// probability (1 - 0.12)^bits_per_key per table, and more tables find more of them.
  int tables = 6;
  int bits_per_key = 16;
  /// Bytes per descriptor (ORB: 32).
  int descriptor_bytes = 32;
  /// Which bit positions the keys take (any fixed value gives a reproducible index).
  std::uint64_t seed = 0x5DEECE66Dull;

  [[nodiscard]] bool IsValid(std::string* why) const;
};

/// Thread-safety: none.
class AppearanceIndex {
 public:
  /// `config` must satisfy IsValid().
  explicit AppearanceIndex(const AppearanceIndexConfig& config = {});

  /// Adds keyframe `id`'s descriptors: `rows` descriptors of descriptor_bytes each, row after row.
  void Add(int id, const std::uint8_t* descriptors, int rows);

  /// The keyframes up to max_id whose descriptors share buckets with the query's, by votes (one
  /// per query descriptor and table that finds the keyframe's descriptor in its bucket), most
  /// first, at most `count`: (votes, id).
  [[nodiscard]] std::vector<std::pair<int, int>> MostAlike(const std::uint8_t* descriptors,
                                                           int rows, int max_id, int count) const;

  [[nodiscard]] int size() const { return keyframes_; }

 private:
  [[nodiscard]] std::uint32_t Key(int table, const std::uint8_t* descriptor) const;

  AppearanceIndexConfig config_;
  std::vector<std::vector<int>> bits_;  // per table: the bit positions of its key
  std::vector<std::unordered_map<std::uint32_t, std::vector<int>>> buckets_;  // key -> ids
  int keyframes_ = 0;
};

}  // namespace objmap
