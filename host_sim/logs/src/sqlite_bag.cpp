#include "dyncal_host/logs/sqlite_bag.hpp"

#include <sqlite3.h>

#include <filesystem>
#include <map>
#include <memory>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

using Db = std::unique_ptr<sqlite3, decltype(&sqlite3_close)>;
using Statement = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

Statement prepare(sqlite3* db, const std::string& sql, const std::string& path) {
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
    const std::string msg = sqlite3_errmsg(db);
    sqlite3_finalize(s);
    throw InputError(path + ": not a rosbag2 SQLite3 file (" + msg + ")");
  }
  return Statement(s, &sqlite3_finalize);
}

std::string text(sqlite3_stmt* s, int col) {
  const unsigned char* t = sqlite3_column_text(s, col);
  return t ? reinterpret_cast<const char*>(t) : "";
}

void finish(sqlite3* db, int rc, const std::string& path) {
  if (rc != SQLITE_DONE) throw InputError(path + ": " + sqlite3_errmsg(db));
}

}  // namespace

BagMessages read_sqlite_bag(const std::string& path, const KeepTopic& keep) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": not a regular file");
  sqlite3* raw = nullptr;
  const int open = sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
  Db db(raw, &sqlite3_close);
  if (open != SQLITE_OK) throw InputError(path + ": cannot be opened (" + sqlite3_errmsg(raw) + ")");
  BagMessages out;
  std::map<sqlite3_int64, int> topic_of;  // topic id -> topics index, or -1 - index when not kept
  {
    Statement s = prepare(db.get(), "SELECT id, name, type, serialization_format FROM topics ORDER BY id", path);
    int rc;
    while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
      const BagTopic t{text(s.get(), 1), text(s.get(), 2), text(s.get(), 3)};
      const int index = static_cast<int>(out.topics.size());
      out.topics.push_back(t);
      topic_of[sqlite3_column_int64(s.get(), 0)] = keep(t) ? index : -1 - index;
    }
    finish(db.get(), rc, path);
  }
  Statement s = prepare(db.get(), "SELECT id, topic_id, timestamp, data FROM messages ORDER BY id", path);
  int rc;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
    const sqlite3_int64 topic_id = sqlite3_column_int64(s.get(), 1);
    const auto t = topic_of.find(topic_id);
    if (t == topic_of.end())
      throw InputError(path + ": message " + std::to_string(sqlite3_column_int64(s.get(), 0)) + " has topic_id " +
                       std::to_string(topic_id) + ", which no topic has");
    if (t->second < 0) continue;
    BagMessage m;
    m.topic = t->second;
    // rosbag2's timestamp column is an INTEGER [ns]: text ('abc') or a real is a corrupt row, not 0.
    if (sqlite3_column_type(s.get(), 2) != SQLITE_INTEGER)
      throw InputError(path + ": message " + std::to_string(sqlite3_column_int64(s.get(), 0)) +
                       ": its timestamp is not an integer number of nanoseconds ('" + excerpt(text(s.get(), 2)) + "')");
    m.log_time = sqlite3_column_int64(s.get(), 2);
    const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s.get(), 3));
    const int n = sqlite3_column_bytes(s.get(), 3);
    if (data && n > 0) m.data.assign(data, data + n);
    out.messages.push_back(std::move(m));
  }
  finish(db.get(), rc, path);
  return out;
}

}  // namespace dyncal::host
