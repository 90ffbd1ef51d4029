#include "store/keyframe_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "store/store_impl.h"
#include "store/store_schema.h"

namespace objmap {

namespace store_internal {

// At most this many idle read connections are kept; more concurrent readers open (and then
// close) their own.
constexpr std::size_t kMaxIdleReaders = 8;

ReaderPool::Lease::~Lease() {
  if (connection_ != nullptr) pool_->Return(std::move(connection_));
}

ReaderPool::Lease ReaderPool::Acquire(std::string* why) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!idle_.empty()) {
      std::unique_ptr<Connection> connection = std::move(idle_.back());
      idle_.pop_back();
      return Lease(this, std::move(connection));
    }
  }
  return Lease(this, OpenReader(path_, busy_timeout_ms_, why));
}

void ReaderPool::Return(std::unique_ptr<Connection> connection) {
  connection->RollbackIfOpen();
  std::lock_guard<std::mutex> lock(mutex_);
  if (idle_.size() < kMaxIdleReaders) idle_.push_back(std::move(connection));
}

std::unique_ptr<WriterLock> WriterLock::Acquire(const std::string& lock_path, std::string* why) {
  const int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) {
    *why = "cannot open the lock file " + lock_path + ": " + std::strerror(errno);
    return nullptr;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    char holder[32] = {};
    const ssize_t read_bytes = ::pread(fd, holder, sizeof(holder) - 1, 0);
    ::close(fd);
    if (error != EWOULDBLOCK) {
      *why = "cannot lock " + lock_path + ": " + std::strerror(error);
      return nullptr;
    }
    std::string pid(holder, read_bytes > 0 ? static_cast<std::size_t>(read_bytes) : 0);
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    *why = "the database is in use by another objmap process (" +
           (pid.empty() ? std::string("pid unknown") : "pid " + pid) + ", holding " + lock_path +
           "); one server per database";
    return nullptr;
  }
  // The holder's pid, for the message above; the lock, not the file, is what counts.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 ||
      ::pwrite(fd, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    // Not fatal: the lock holds; only the message naming the holder is poorer.
  }
  return std::unique_ptr<WriterLock>(new WriterLock(fd));
}

WriterLock::~WriterLock() { ::close(fd_); }  // closing the descriptor releases the flock

// Creates the database file readable and writable by its owner only (SQLite would use 0644);
// SQLite gives its -wal and -shm files the database's permissions. An existing file is left as
// it is: its owner chose its mode.
bool CreateOwnerOnly(const std::string& path, std::string* why) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd >= 0) {
    ::close(fd);  // an empty file is an empty SQLite database
    return true;
  }
  if (errno == EEXIST) return true;
  *why = path + ": cannot create: " + std::strerror(errno);
  return false;
}

}  // namespace store_internal

bool KeyframeStoreConfig::IsValid(std::string* why) const {
  if (color_jpeg_quality < 1 || color_jpeg_quality > 100) {
    *why = "color_jpeg_quality must be in 1..100, is " + std::to_string(color_jpeg_quality);
    return false;
  }
  if (busy_timeout_ms < 0) {
    *why = "busy_timeout_ms must be >= 0, is " + std::to_string(busy_timeout_ms);
    return false;
  }
  if (synchronous != "OFF" && synchronous != "NORMAL" && synchronous != "FULL") {
    *why = "synchronous must be OFF, NORMAL or FULL, is \"" + synchronous + "\"";
    return false;
  }
  return true;
}

KeyframeStore::KeyframeStore() : impl_(std::make_unique<Impl>()) {}

KeyframeStore::~KeyframeStore() = default;

std::unique_ptr<KeyframeStore> KeyframeStore::Open(const std::string& path,
                                                   const KeyframeStoreConfig& config,
                                                   std::string* why) {
  if (!config.IsValid(why)) {
    *why = path + ": invalid store config: " + *why;
    return nullptr;
  }
  // Temporary and in-memory databases would give every read connection its own database.
  if (path.empty() || path == ":memory:" || path.rfind("file:", 0) == 0) {
    *why = "\"" + path + "\": the store needs a file path";
    return nullptr;
  }
  std::unique_ptr<KeyframeStore> store(new KeyframeStore());
  store->impl_->lock = store_internal::WriterLock::Acquire(path + ".lock", why);
  if (!store->impl_->lock) {
    *why = path + ": " + *why;
    return nullptr;
  }
  if (!store_internal::CreateOwnerOnly(path, why)) return nullptr;
  store->impl_->path = path;
  store->impl_->config = config;
  store->impl_->writer = store_internal::OpenWriter(path, config, why);
  if (!store->impl_->writer) return nullptr;
  store->impl_->readers =
      std::make_unique<store_internal::ReaderPool>(path, config.busy_timeout_ms);
  return store;
}

std::size_t KeyframeStore::NumKeyframes() const {
  std::string why;
  auto reader = impl_->readers->Acquire(&why);
  std::int64_t count = 0;
  if (!reader || !reader.get()->QueryInt("SELECT count(*) FROM keyframes", &count, &why)) return 0;
  return static_cast<std::size_t>(count);
}

std::uint64_t KeyframeStore::FileBytes() const {
  std::uint64_t total = 0;
  for (const std::string& file : {impl_->path, impl_->path + "-wal"}) {
    std::error_code error;
    const auto bytes = std::filesystem::file_size(file, error);
    if (!error) total += bytes;
  }
  return total;
}

KeyframeStore::KeyframeBytes KeyframeStore::BytesOf(KeyframeId id) const {
  KeyframeBytes bytes;
  std::string why;
  auto reader = impl_->readers->Acquire(&why);
  if (!reader || !reader.get()->Exec("BEGIN", &why)) return bytes;
  auto row = reader.get()->Prepare(
      "SELECT length(depth_png), length(mask_png), ifnull(length(color_jpeg), 0),"
      " length(T_W_C) + length(detections) FROM keyframes WHERE id = ?",
      "keyframe sizes", &why);
  auto observations = reader.get()->Prepare(
      "SELECT ifnull(sum(length(class_scores) + length(points) + length(colors) +"
      " length(pixels)), 0)"
      " FROM observations WHERE keyframe_id = ?",
      "observation sizes", &why);
  bool has_row = false;
  if (!row || !observations || !row->Bind(1, std::int64_t{id}).Step(&has_row, &why) || !has_row ||
      !observations->Bind(1, std::int64_t{id}).Step(&has_row, &why)) {
    return bytes;
  }
  bytes.depth = row->Int64(0);
  bytes.mask = row->Int64(1);
  bytes.color = row->Int64(2);
  bytes.observations = observations->Int64(0);
  bytes.total = bytes.depth + bytes.mask + bytes.color + bytes.observations + row->Int64(3);
  return bytes;
}

const std::string& KeyframeStore::path() const { return impl_->path; }

}  // namespace objmap
