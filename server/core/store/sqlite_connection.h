#pragma once
// Thin RAII wrappers over one sqlite3 connection and its prepared statements. Internal to the
// store module (sqlite3.h stays out of the public header).

#include <sqlite3.h>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace objmap {
namespace store_internal {

/// A prepared statement borrowed from a Connection's cache. Binding errors are remembered and
/// reported by the next Step/Run, so call sites bind without checking each call. Resets the
/// statement (and clears its bindings) when it goes out of scope. Not copyable.
class Statement {
 public:
  Statement(sqlite3_stmt* stmt, sqlite3* db, std::string label);
  Statement(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  Statement& operator=(Statement&&) = delete;
  ~Statement();

  Statement& Bind(int index, std::int64_t value);
  Statement& Bind(int index, double value);
  Statement& Bind(int index, const std::string& text);
  /// A zero-length blob is stored as an empty blob, never as NULL.
  Statement& BindBlob(int index, const void* data, std::size_t bytes);
  Statement& BindNull(int index);

  /// Steps once: true with *has_row telling whether a row came; false with a reason
  /// "<label>: <sqlite message>" on failure.
  [[nodiscard]] bool Step(bool* has_row, std::string* why);
  /// Steps to completion of a statement that returns no rows.
  [[nodiscard]] bool Run(std::string* why);

  [[nodiscard]] std::int64_t Int64(int column) const;
  [[nodiscard]] double Double(int column) const;
  [[nodiscard]] std::string Text(int column) const;
  [[nodiscard]] bool IsNull(int column) const;
  /// Blob bytes of a column (nullptr with 0 bytes when empty); valid until the next Step.
  [[nodiscard]] const std::uint8_t* Blob(int column, std::size_t* bytes) const;

  /// Extended result code of the last failed Step (SQLITE_OK when none failed).
  [[nodiscard]] int error_code() const { return error_code_; }

 private:
  void Remember(int rc);

  sqlite3_stmt* stmt_;
  sqlite3* db_;
  std::string label_;
  int bind_rc_ = SQLITE_OK;
  int error_code_ = SQLITE_OK;
};

/// One sqlite3 connection with a cache of prepared statements (prepared once, reused: the
/// store runs the same few statements for every keyframe). Thread-safety: none; the owner
/// hands a connection to one thread at a time.
class Connection {
 public:
  /// Opens `path` with `flags` (SQLITE_OPEN_*). nullptr and a reason on failure.
  static std::unique_ptr<Connection> Open(const std::string& path, int flags, int busy_timeout_ms,
                                          std::string* why);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  /// Runs SQL without results (several statements allowed). Reason "<sql>: <message>".
  [[nodiscard]] bool Exec(const std::string& sql, std::string* why);
  /// A cached statement for `sql`; `label` names it in error reasons. Empty (and a reason) when
  /// the statement does not compile, e.g. a table is missing.
  [[nodiscard]] std::optional<Statement> Prepare(const std::string& sql, const std::string& label,
                                                 std::string* why);
  /// The first column of the first row of `sql` as an integer.
  [[nodiscard]] bool QueryInt(const std::string& sql, std::int64_t* value, std::string* why);
  /// Rolls back the open transaction, if any (after a failure; errors are ignored).
  void RollbackIfOpen();

  [[nodiscard]] sqlite3* db() const { return db_; }
  [[nodiscard]] int changes() const { return sqlite3_changes(db_); }

 private:
  explicit Connection(sqlite3* db) : db_(db) {}

  sqlite3* db_;
  std::map<std::string, sqlite3_stmt*> cache_;
};

}  // namespace store_internal
}  // namespace objmap
