#include "map_server/task_threads.h"

#include <pthread.h>

#include <algorithm>
#include <cstdio>

#include "map_server/fairness.h"

namespace objmap {

TaskThreads::TaskThreads(const Options& options) : max_waiting_(options.max_waiting) {
  for (int t = 0; t < options.threads; ++t) {
    threads_.emplace_back([this, options] { Loop(options); });
  }
}

TaskThreads::~TaskThreads() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  queued_.notify_all();
  for (std::thread& thread : threads_) thread.join();
}

bool TaskThreads::Run(const std::function<void()>& task) {
  Task entry;
  entry.run = &task;
  std::unique_lock<std::mutex> lock(mutex_);
  // Queued tasks beyond the idle threads wait.
  const int idle = static_cast<int>(threads_.size()) - running_;
  if (max_waiting_ >= 0 && static_cast<int>(tasks_.size()) - idle >= max_waiting_) return false;
  tasks_.push_back(&entry);
  queued_.notify_one();
  finished_.wait(lock, [&entry] { return entry.done; });
  if (entry.error) std::rethrow_exception(entry.error);
  return true;
}

int TaskThreads::waiting() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::max(0, static_cast<int>(tasks_.size()) -
                         (static_cast<int>(threads_.size()) - running_));
}

void TaskThreads::Loop(const Options& options) {
  pthread_setname_np(pthread_self(), options.name.substr(0, 15).c_str());
  std::string why;
  if (!LowerThisThreadPriority(options.nice, &why)) {
    // The tasks still run, only without the lower priority.
    std::fprintf(stderr, "objmap: %s: %s\n", options.name.c_str(), why.c_str());
  }
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    queued_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
    if (tasks_.empty()) return;  // stopping, and nothing left to run
    Task* task = tasks_.front();
    tasks_.pop_front();
    ++running_;
    lock.unlock();
    std::exception_ptr error;
    try {
      (*task->run)();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    --running_;
    task->error = error;
    task->done = true;
    finished_.notify_all();
  }
}

}  // namespace objmap
