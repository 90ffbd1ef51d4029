// TaskThreads (the server's detector and heavy-query threads): tasks run on the threads, in
// order, at the priority asked for; a full queue refuses at once; exceptions reach the caller.

#include "map_server/task_threads.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "map_server/fairness.h"

namespace objmap {
namespace {

using namespace std::chrono_literals;

constexpr auto kPatience = 20s;

int ThisThreadNice() {
  return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
}

std::string ThisThreadName() {
  char name[16] = {};
  pthread_getname_np(pthread_self(), name, sizeof(name));
  return name;
}

// Waits until `threads` has `count` tasks waiting.
bool WaitForWaiting(const TaskThreads& threads, int count) {
  const auto deadline = std::chrono::steady_clock::now() + kPatience;
  while (threads.waiting() < count && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(1ms);
  }
  return threads.waiting() == count;
}

TEST(TaskThreads, RunsTasksOnItsThreadsInOrderAtTheLowerPriority) {
  TaskThreads::Options options;
  options.threads = 1;
  options.nice = 3;
  options.name = "objmap-test";
  TaskThreads threads(options);
  const int caller_nice = ThisThreadNice();
  std::thread::id ran_on;
  int nice = -100;
  std::string name;
  ASSERT_TRUE(threads.Run([&] {
    ran_on = std::this_thread::get_id();
    nice = ThisThreadNice();
    name = ThisThreadName();
  }));
  EXPECT_NE(ran_on, std::this_thread::get_id());
  // Relative to the creator's niceness (the test may itself run niced); capped at 19.
  EXPECT_EQ(nice, std::min(19, caller_nice + 3));
  EXPECT_EQ(name, "objmap-test");
  EXPECT_EQ(ThisThreadNice(), caller_nice) << "the caller's priority changed";

  // While the thread is held, tasks from several callers queue; they run in the order handed.
  std::promise<void> started, release;
  std::future<bool> holder = std::async(std::launch::async, [&] {
    return threads.Run([&, released = release.get_future().share()] {
      started.set_value();
      released.wait();
    });
  });
  started.get_future().wait();
  std::mutex mutex;
  std::vector<int> order;
  std::vector<std::future<bool>> calls;
  for (int i = 0; i < 6; ++i) {
    calls.push_back(std::async(std::launch::async, [&, i] {
      return threads.Run([&, i] {
        std::lock_guard<std::mutex> lock(mutex);
        order.push_back(i);
      });
    }));
    ASSERT_TRUE(WaitForWaiting(threads, i + 1));
  }
  release.set_value();
  EXPECT_TRUE(holder.get());
  for (auto& call : calls) EXPECT_TRUE(call.get());
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

TEST(TaskThreads, AFullQueueRefusesAtOnceAndExceptionsReachTheCaller) {
  TaskThreads::Options options;
  options.threads = 1;
  options.max_waiting = 1;
  TaskThreads threads(options);
  std::promise<void> started, release;
  std::shared_future<void> released = release.get_future().share();
  // The first task holds the thread; the second waits; the third is refused.
  std::future<bool> first = std::async(std::launch::async, [&] {
    return threads.Run([&] {
      started.set_value();
      released.wait();
    });
  });
  started.get_future().wait();
  EXPECT_EQ(threads.waiting(), 0);
  std::future<bool> second =
      std::async(std::launch::async, [&] { return threads.Run([] {}); });
  ASSERT_TRUE(WaitForWaiting(threads, 1));
  bool third_ran = false;
  EXPECT_FALSE(threads.Run([&] { third_ran = true; }));
  EXPECT_FALSE(third_ran);
  release.set_value();
  EXPECT_TRUE(first.get());
  EXPECT_TRUE(second.get());
  EXPECT_THROW((void)threads.Run([] { throw std::runtime_error("task failed"); }),
               std::runtime_error);
  EXPECT_TRUE(threads.Run([] {})) << "the thread survives a task's exception";
}

TEST(Fairness, ConfigIsValidated) {
  std::string why;
  FairnessConfig config;
  EXPECT_TRUE(config.IsValid(&why)) << why;
  config.heavy_query_threads = 0;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("heavy_query_threads"), std::string::npos) << why;
  config = FairnessConfig();
  config.heavy_query_nice = 20;
  EXPECT_FALSE(config.IsValid(&why));
  EXPECT_NE(why.find("heavy_query_nice"), std::string::npos) << why;
  config = FairnessConfig();
  config.max_waiting_heavy_queries = -1;
  EXPECT_FALSE(config.IsValid(&why));
}

}  // namespace
}  // namespace objmap
