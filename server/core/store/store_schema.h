#pragma once
// Opening the store's SQLite file: recognising an objmap database (or creating one), and the
// connection settings every connection needs.

#include <cstdint>
#include <memory>
#include <string>

#include "store/keyframe_store.h"
#include "store/sqlite_connection.h"

namespace objmap {
namespace store_internal {

/// PRAGMA application_id of objmap databases ("OBJM"): tells them apart from other SQLite files
/// that happen to use user_version.
constexpr std::int32_t kApplicationId = 0x4F424A4D;

/// Opens the write connection: checks that `path` is SQLite, not corrupt (quick_check) and an
/// objmap database of a known schema version, or creates the schema in a new (empty) file in
/// one transaction; then sets WAL, synchronous and foreign keys. nullptr and a reason naming
/// `path` otherwise.
[[nodiscard]] std::unique_ptr<Connection> OpenWriter(const std::string& path,
                                                     const KeyframeStoreConfig& config,
                                                     std::string* why);

/// Opens a read-only connection to an existing objmap database (WAL lets it read while the
/// writer commits).
[[nodiscard]] std::unique_ptr<Connection> OpenReader(const std::string& path, int busy_timeout_ms,
                                                     std::string* why);

}  // namespace store_internal
}  // namespace objmap
