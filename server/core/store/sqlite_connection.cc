#include "store/sqlite_connection.h"

#include <utility>

namespace objmap {
namespace store_internal {

Statement::Statement(sqlite3_stmt* stmt, sqlite3* db, std::string label)
    : stmt_(stmt), db_(db), label_(std::move(label)) {}

Statement::Statement(Statement&& other) noexcept
    : stmt_(other.stmt_),
      db_(other.db_),
      label_(std::move(other.label_)),
      bind_rc_(other.bind_rc_),
      error_code_(other.error_code_) {
  other.stmt_ = nullptr;
}

Statement::~Statement() {
  if (stmt_ != nullptr) {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
}

void Statement::Remember(int rc) {
  if (rc != SQLITE_OK && bind_rc_ == SQLITE_OK) bind_rc_ = rc;
}

Statement& Statement::Bind(int index, std::int64_t value) {
  Remember(sqlite3_bind_int64(stmt_, index, value));
  return *this;
}

Statement& Statement::Bind(int index, double value) {
  Remember(sqlite3_bind_double(stmt_, index, value));
  return *this;
}

Statement& Statement::Bind(int index, const std::string& text) {
  Remember(sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()),
                             SQLITE_TRANSIENT));
  return *this;
}

Statement& Statement::BindBlob(int index, const void* data, std::size_t bytes) {
  // sqlite3_bind_blob with a null pointer binds NULL; an empty blob needs zeroblob(0).
  if (bytes == 0) {
    Remember(sqlite3_bind_zeroblob(stmt_, index, 0));
  } else {
    Remember(sqlite3_bind_blob64(stmt_, index, data, bytes, SQLITE_STATIC));
  }
  return *this;
}

Statement& Statement::BindNull(int index) {
  Remember(sqlite3_bind_null(stmt_, index));
  return *this;
}

bool Statement::Step(bool* has_row, std::string* why) {
  if (bind_rc_ != SQLITE_OK) {
    error_code_ = bind_rc_;
    *why = label_ + ": binding failed: " + sqlite3_errstr(bind_rc_);
    return false;
  }
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW || rc == SQLITE_DONE) {
    *has_row = rc == SQLITE_ROW;
    return true;
  }
  error_code_ = sqlite3_extended_errcode(db_);
  *why = label_ + ": " + sqlite3_errmsg(db_);
  return false;
}

bool Statement::Run(std::string* why) {
  bool has_row = true;
  while (has_row) {
    if (!Step(&has_row, why)) return false;
  }
  return true;
}

std::int64_t Statement::Int64(int column) const { return sqlite3_column_int64(stmt_, column); }

double Statement::Double(int column) const { return sqlite3_column_double(stmt_, column); }

std::string Statement::Text(int column) const {
  const auto* text = sqlite3_column_text(stmt_, column);
  const int bytes = sqlite3_column_bytes(stmt_, column);
  return text == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(text), bytes);
}

bool Statement::IsNull(int column) const {
  return sqlite3_column_type(stmt_, column) == SQLITE_NULL;
}

const std::uint8_t* Statement::Blob(int column, std::size_t* bytes) const {
  const void* data = sqlite3_column_blob(stmt_, column);
  *bytes = data == nullptr ? 0 : static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column));
  return static_cast<const std::uint8_t*>(data);
}

std::unique_ptr<Connection> Connection::Open(const std::string& path, int flags,
                                             int busy_timeout_ms, std::string* why) {
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(path.c_str(), &db, flags, nullptr);
  if (rc != SQLITE_OK) {
    *why = path + ": cannot open: " + (db != nullptr ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
    sqlite3_close(db);
    return nullptr;
  }
  sqlite3_extended_result_codes(db, 1);
  sqlite3_busy_timeout(db, busy_timeout_ms);
  return std::unique_ptr<Connection>(new Connection(db));
}

Connection::~Connection() {
  for (auto& [sql, stmt] : cache_) sqlite3_finalize(stmt);
  sqlite3_close(db_);
}

bool Connection::Exec(const std::string& sql, std::string* why) {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) == SQLITE_OK) return true;
  *why = sql + ": " + (message != nullptr ? message : sqlite3_errmsg(db_));
  sqlite3_free(message);
  return false;
}

std::optional<Statement> Connection::Prepare(const std::string& sql, const std::string& label,
                                             std::string* why) {
  auto it = cache_.find(sql);
  if (it == cache_.end()) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v3(db_, sql.c_str(), static_cast<int>(sql.size()),
                           SQLITE_PREPARE_PERSISTENT, &stmt, nullptr) != SQLITE_OK) {
      *why = label + ": " + sqlite3_errmsg(db_);
      return std::nullopt;
    }
    it = cache_.emplace(sql, stmt).first;
  }
  return Statement(it->second, db_, label);
}

bool Connection::QueryInt(const std::string& sql, std::int64_t* value, std::string* why) {
  auto statement = Prepare(sql, sql, why);
  bool has_row = false;
  if (!statement || !statement->Step(&has_row, why)) return false;
  *value = has_row ? statement->Int64(0) : 0;
  return true;
}

void Connection::RollbackIfOpen() {
  if (sqlite3_get_autocommit(db_) == 0) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
}

}  // namespace store_internal
}  // namespace objmap
