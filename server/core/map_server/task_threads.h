#pragma once
// Private to map_server: threads of the server's own that run tasks handed to them.

#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace objmap {

/// Threads that run the tasks handed to them in the order handed, each task on one of them;
/// Run() returns once its task has run. Work done here keeps the priority these threads were
/// given, whatever the caller's. Thread-safety: Run() from any thread.
class TaskThreads {
 public:
  struct Options {
    int threads = 1;
    /// Niceness the threads add to their own at start (lower priority); 0: the creator's.
    int nice = 0;
    /// Tasks that may wait for a thread; Run() refuses one more. Negative: no limit.
    int max_waiting = -1;
    /// Thread name (at most 15 characters), for ps, top and debuggers.
    std::string name = "objmap-task";
  };

  explicit TaskThreads(const Options& options);
  /// Runs the tasks still queued, then joins the threads.
  ~TaskThreads();
  TaskThreads(const TaskThreads&) = delete;
  TaskThreads& operator=(const TaskThreads&) = delete;

  /// Runs `task` on one of the threads and returns true once it has run; an exception it
  /// throws is thrown here. False at once, without running it, when max_waiting tasks wait.
  [[nodiscard]] bool Run(const std::function<void()>& task);

  /// Tasks handed in and not yet started, beyond those an idle thread is about to take.
  [[nodiscard]] int waiting() const;

 private:
  struct Task {
    const std::function<void()>* run = nullptr;
    bool done = false;
    std::exception_ptr error;
  };
  void Loop(const Options& options);

  const int max_waiting_;
  mutable std::mutex mutex_;
  std::condition_variable queued_, finished_;
  std::deque<Task*> tasks_;
  bool stopping_ = false;
  int running_ = 0;  // tasks being run
  std::vector<std::thread> threads_;
};

}  // namespace objmap
