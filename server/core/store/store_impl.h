#pragma once
// State shared by the store's translation units (keyframe_store.cc, keyframe_store_load.cc).

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "store/keyframe_store.h"
#include "store/sqlite_connection.h"

namespace objmap {
namespace store_internal {

/// Read connections handed to one caller at a time, so that const methods run concurrently with
/// each other and with Commit (WAL: readers see the last committed state and never block the
/// writer). Thread-safe.
class ReaderPool {
 public:
  /// A borrowed connection, returned to the pool on destruction.
  class Lease {
   public:
    Lease(ReaderPool* pool, std::unique_ptr<Connection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    Lease(Lease&&) = default;
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Lease& operator=(Lease&&) = delete;
    ~Lease();
    [[nodiscard]] Connection* get() const { return connection_.get(); }
    explicit operator bool() const { return connection_ != nullptr; }

   private:
    ReaderPool* pool_;
    std::unique_ptr<Connection> connection_;
  };

  ReaderPool(std::string path, int busy_timeout_ms)
      : path_(std::move(path)), busy_timeout_ms_(busy_timeout_ms) {}
  /// An idle connection or a new one; an empty lease and a reason when none can be opened.
  [[nodiscard]] Lease Acquire(std::string* why);

 private:
  void Return(std::unique_ptr<Connection> connection);

  const std::string path_;
  const int busy_timeout_ms_;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Connection>> idle_;
};

/// An exclusive flock on a database's lock file, which holds the owner's pid: one store (and so
/// one server) per database. Released when destroyed or when the process ends.
class WriterLock {
 public:
  /// The lock on `lock_path` (created 0600), or nullptr and a reason naming the holder.
  static std::unique_ptr<WriterLock> Acquire(const std::string& lock_path, std::string* why);
  ~WriterLock();
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;

 private:
  explicit WriterLock(int fd) : fd_(fd) {}
  int fd_;
};

}  // namespace store_internal

struct KeyframeStore::Impl {
  std::string path;
  /// Taken before the database is opened, released after it is closed (declared first).
  std::unique_ptr<store_internal::WriterLock> lock;
  KeyframeStoreConfig config;
  /// Serializes Commit on the one write connection.
  std::mutex write_mutex;
  std::unique_ptr<store_internal::Connection> writer;
  /// Declared after `writer`, destroyed before it: the writer, closing last, checkpoints the WAL.
  std::unique_ptr<store_internal::ReaderPool> readers;
};

}  // namespace objmap
