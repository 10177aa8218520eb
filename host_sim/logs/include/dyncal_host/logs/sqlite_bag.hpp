#pragma once
// A rosbag2 SQLite3 storage file (.db3; Humble's default): table `topics(id, name, type,
// serialization_format, ...)` and `messages(id, topic_id, timestamp, data)`, read through Debian's
// libsqlite3, read-only.

#include <string>

#include "dyncal_host/logs/bag_messages.hpp"

namespace dyncal::host {

/// Reads the .db3 file at `path`: every topic, and the messages of the kept topics in the order of
/// their row id (the order the recorder wrote them). Throws InputError on one line naming the file:
/// not a SQLite database, no `topics`/`messages` table or column, a corrupt page (SQLite's message),
/// a message whose topic_id no topic has.
BagMessages read_sqlite_bag(const std::string& path, const KeepTopic& keep);

}  // namespace dyncal::host
