// SharedOccupancyMap: the published map equals integrating the same scans into one OccupancyMap,
// readers never wait for the writer (with the second copy) and always see a whole map, and the
// writer waits only for readers of the copy it is about to write.

#include "occupancy/shared_occupancy_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "occupancy/rendered_scans.h"

namespace objmap {
namespace {

using namespace std::chrono_literals;
using testing::CameraSetup;
using testing::Pose;
using testing::Render;

// Long enough for any wait that is not meant to happen to end on a loaded machine; a wait that
// is meant to happen is never cut short by it.
constexpr auto kPatience = 20s;
// How long a wait that must not end is watched (it would end in microseconds).
constexpr auto kWatch = 300ms;

// Coarse voxels keep the maps small: what is tested does not depend on their size.
OccupancyConfig CoarseConfig() {
  OccupancyConfig config;
  config.resolution_m = 0.04;
  return config;
}

std::vector<DepthScanW> Walk(int count) {
  std::vector<DepthScanW> scans;
  for (int k = 0; k < count; ++k) {
    CameraSetup camera;
    camera.T_W_C =
        Pose({-0.8f + 0.2f * static_cast<float>(k), -0.5f + 0.1f * static_cast<float>(k), 0.35f},
             0.6f - 0.15f * static_cast<float>(k), 0.3f, 0.f);
    scans.push_back(Render(camera));
  }
  return scans;
}

// The full state (every node's log-odds) of a plain map after each prefix of the scans:
// [k] holds scans 0 .. k - 1.
std::vector<std::string> PrefixStates(const OccupancyConfig& config,
                                      const std::vector<DepthScanW>& scans) {
  OccupancyMap reference(config);
  std::vector<std::string> states{reference.WriteState()};
  for (const DepthScanW& scan : scans) {
    reference.Integrate(scan);
    states.push_back(reference.WriteState());
  }
  return states;
}

std::string PublishedState(const SharedOccupancyMap& shared) {
  std::string state;
  shared.Read([&](const OccupancyMap& map) { state = map.WriteState(); });
  return state;
}

class SharedOccupancyMapTest : public ::testing::TestWithParam<bool> {};

TEST_P(SharedOccupancyMapTest, PublishesWhatOneMapIntegratingTheSameScansHolds) {
  const OccupancyConfig config = CoarseConfig();
  const std::vector<DepthScanW> scans = Walk(6);
  const std::vector<std::string> states = PrefixStates(config, scans);
  SharedOccupancyMap shared(config, /*second_copy=*/GetParam());
  // Scans alternate between the copies: each is written into one and caught up in the other.
  for (std::size_t k = 0; k < 4; ++k) {
    shared.Integrate(scans[k]);
    ASSERT_EQ(PublishedState(shared), states[k + 1]) << "after scan " << k;
    EXPECT_EQ(shared.latest().WriteState(), states[k + 1]);
  }
  // A rewrite (here: the first two scans again from an empty map) is published, and the copy it
  // is cloned into takes the scans after it.
  ASSERT_TRUE(shared.Rewrite([&](OccupancyMap* map) {
    map->Clear();
    map->Integrate(scans[0]);
    map->Integrate(scans[1]);
    return true;
  }));
  EXPECT_EQ(PublishedState(shared), states[2]);
  OccupancyMap reference(config);
  for (int k : {0, 1, 4, 5}) reference.Integrate(scans[k]);
  shared.Integrate(scans[4]);
  shared.Integrate(scans[5]);
  EXPECT_EQ(PublishedState(shared), reference.WriteState());
  shared.CatchUp();
  shared.Integrate(scans[2]);
  reference.Integrate(scans[2]);
  EXPECT_EQ(PublishedState(shared), reference.WriteState());
  // A refused rewrite publishes nothing.
  EXPECT_FALSE(shared.Rewrite([](OccupancyMap*) { return false; }));
  EXPECT_EQ(PublishedState(shared), reference.WriteState());
  shared.Integrate(scans[3]);
  reference.Integrate(scans[3]);
  EXPECT_EQ(PublishedState(shared), reference.WriteState());

  // A rebuild starts from an empty map; one that fails publishes nothing, and the copy it
  // emptied is made equal again before the next write.
  bool started_empty = false;
  ASSERT_TRUE(shared.Rebuild([&](OccupancyMap* map) {
    started_empty = map->Counts().occupied == 0 && map->Counts().free == 0;
    for (int k : {0, 1, 2}) map->Integrate(scans[k]);
    return true;
  }));
  EXPECT_TRUE(started_empty);
  EXPECT_EQ(PublishedState(shared), states[3]);
  if (GetParam()) {  // with one copy a failed rebuild leaves it empty (see Rebuild)
    EXPECT_FALSE(shared.Rebuild([](OccupancyMap*) { return false; }));
    EXPECT_EQ(PublishedState(shared), states[3]);
  }
  shared.Integrate(scans[3]);
  EXPECT_EQ(PublishedState(shared), states[4]);
  shared.Integrate(scans[4]);
  EXPECT_EQ(PublishedState(shared), states[5]);
}

INSTANTIATE_TEST_SUITE_P(Copies, SharedOccupancyMapTest, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "TwoCopies" : "OneCopy";
                         });

// A write that takes as long as the test wants: Rewrite() with a callback that waits.
struct HeldWrite {
  std::promise<void> entered, release;
  std::future<bool> done;

  HeldWrite(SharedOccupancyMap* shared, const DepthScanW& scan) {
    std::future<void> released = release.get_future();
    done = std::async(std::launch::async, [this, shared, &scan, released = std::move(released)] {
      return shared->Rewrite([&](OccupancyMap* map) {
        entered.set_value();
        released.wait();
        map->Integrate(scan);
        return true;
      });
    });
    entered.get_future().wait();
  }
};

std::future<std::string> ReadAsync(const SharedOccupancyMap& shared) {
  return std::async(std::launch::async, [&shared] { return PublishedState(shared); });
}

TEST(SharedOccupancyMap, AReaderDoesNotWaitForAWriteInProgress) {
  const OccupancyConfig config = CoarseConfig();
  const std::vector<DepthScanW> scans = Walk(2);
  const std::vector<std::string> states = PrefixStates(config, scans);
  SharedOccupancyMap shared(config);
  shared.Integrate(scans[0]);
  HeldWrite write(&shared, scans[1]);
  std::future<std::string> read = ReadAsync(shared);
  ASSERT_EQ(read.wait_for(kPatience), std::future_status::ready)
      << "a reader waited for the writer";
  EXPECT_EQ(read.get(), states[1]) << "a reader saw a write before it was published";
  write.release.set_value();
  ASSERT_TRUE(write.done.get());
  EXPECT_EQ(PublishedState(shared), states[2]);
}

TEST(SharedOccupancyMap, WithOneCopyAReaderWaitsForTheWrite) {
  const OccupancyConfig config = CoarseConfig();
  const std::vector<DepthScanW> scans = Walk(2);
  const std::vector<std::string> states = PrefixStates(config, scans);
  SharedOccupancyMap shared(config, /*second_copy=*/false);
  shared.Integrate(scans[0]);
  HeldWrite write(&shared, scans[1]);
  std::future<std::string> read = ReadAsync(shared);
  EXPECT_EQ(read.wait_for(kWatch), std::future_status::timeout)
      << "a reader read the one copy while it was written";
  write.release.set_value();
  ASSERT_TRUE(write.done.get());
  EXPECT_EQ(read.get(), states[2]);
}

TEST(SharedOccupancyMap, AWriterWaitsOnlyForReadersOfTheCopyItWrites) {
  const OccupancyConfig config = CoarseConfig();
  const std::vector<DepthScanW> scans = Walk(3);
  const std::vector<std::string> states = PrefixStates(config, scans);
  SharedOccupancyMap shared(config);
  // A long query on the published map.
  std::promise<void> reading, finish_reading;
  std::future<void> read_done = std::async(std::launch::async, [&] {
    shared.Read([&](const OccupancyMap&) {
      reading.set_value();
      finish_reading.get_future().wait();
    });
  });
  reading.get_future().wait();
  // The next scan goes into the other copy: no wait, and later readers see it.
  std::future<void> first =
      std::async(std::launch::async, [&] { shared.Integrate(scans[0]); });
  ASSERT_EQ(first.wait_for(kPatience), std::future_status::ready)
      << "the writer waited for a reader of the other copy";
  EXPECT_EQ(ReadAsync(shared).get(), states[1]);
  // The one after must first bring the long query's copy up to date: it waits for the query.
  std::future<void> second =
      std::async(std::launch::async, [&] { shared.Integrate(scans[1]); });
  EXPECT_EQ(second.wait_for(kWatch), std::future_status::timeout)
      << "the writer changed a copy while a reader was on it";
  // Meanwhile queries are still answered, from the latest published map.
  std::future<std::string> meanwhile = ReadAsync(shared);
  ASSERT_EQ(meanwhile.wait_for(kPatience), std::future_status::ready);
  EXPECT_EQ(meanwhile.get(), states[1]);
  finish_reading.set_value();
  read_done.get();
  ASSERT_EQ(second.wait_for(kPatience), std::future_status::ready);
  EXPECT_EQ(PublishedState(shared), states[2]);
}

TEST(SharedOccupancyMap, ReadersUnderConstantWritesSeeWholeMapsInOrder) {
  const OccupancyConfig config = CoarseConfig();
  const std::vector<DepthScanW> scans = Walk(8);
  const std::vector<std::string> states = PrefixStates(config, scans);
  SharedOccupancyMap shared(config);
  std::atomic<bool> writing{true};
  std::vector<std::vector<int>> seen(3);
  std::vector<std::thread> readers;
  for (std::size_t r = 0; r < seen.size(); ++r) {
    readers.emplace_back([&, r] {
      while (writing) {
        shared.Read([&](const OccupancyMap& map) {
          const std::string state = map.WriteState();
          const auto it = std::find(states.begin(), states.end(), state);
          seen[r].push_back(it == states.end() ? -1 : static_cast<int>(it - states.begin()));
          // Unchanged while it is read.
          if (map.WriteState() != state) seen[r].push_back(-2);
        });
      }
    });
  }
  for (const DepthScanW& scan : scans) {
    shared.Integrate(scan);
    std::this_thread::sleep_for(2ms);
  }
  writing = false;
  for (std::thread& reader : readers) reader.join();
  for (const std::vector<int>& prefixes : seen) {
    ASSERT_FALSE(prefixes.empty());
    for (std::size_t i = 0; i < prefixes.size(); ++i) {
      ASSERT_GE(prefixes[i], 0) << (prefixes[i] == -2 ? "the map changed during a read"
                                                      : "a reader saw a map no prefix makes");
      if (i > 0) {
        ASSERT_GE(prefixes[i], prefixes[i - 1]) << "a reader saw an older map later";
      }
    }
  }
  EXPECT_EQ(PublishedState(shared), states.back());
}

}  // namespace
}  // namespace objmap
