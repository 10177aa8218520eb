#include "dyncal_host/logs/ros2_bag.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/decompression_budget.hpp"
#include "dyncal_host/logs/joint_state_cdr.hpp"
#include "dyncal_host/logs/mcap_reader.hpp"
#include "dyncal_host/logs/sample_clock.hpp"
#include "dyncal_host/logs/sqlite_bag.hpp"

namespace dyncal::host {
namespace {

namespace fs = std::filesystem;
constexpr const char* kJointState = "sensor_msgs/msg/JointState";

enum class Storage { none, mcap, sqlite3 };

Storage storage_of_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  in.read(head, sizeof head);
  if (in.gcount() >= 8 && std::memcmp(head, "\x89MCAP0\r\n", 8) == 0) return Storage::mcap;
  if (in.gcount() == 16 && std::memcmp(head, "SQLite format 3", 16) == 0) return Storage::sqlite3;
  return Storage::none;
}

/// One storage file of a bag; `zstd` when rosbag2 compressed the whole file (compression_mode FILE).
struct StorageFile {
  std::string path;
  bool zstd = false;
};

struct BagLayout {
  std::vector<StorageFile> files;
  bool zstd_messages = false;  ///< compression_mode MESSAGE: each message's data is a zstd frame
};

BagLayout layout_of(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return {{{path, false}}, false};
  const std::string meta = (fs::path(path) / "metadata.yaml").string();
  if (!fs::is_regular_file(meta, ec))
    throw InputError(path + ": a folder without metadata.yaml is not a rosbag2 bag (give its .mcap or .db3 file)");
  try {
    const YAML::Node info = YAML::LoadFile(meta)["rosbag2_bagfile_information"];
    if (!info) throw InputError(meta + ": no rosbag2_bagfile_information");
    const std::string storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
    if (storage != "mcap" && storage != "sqlite3")
      throw InputError(meta + ": storage_identifier '" + storage + "' is not mcap or sqlite3");
    const std::string format = info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    const std::string mode = info["compression_mode"] ? info["compression_mode"].as<std::string>() : "";
    if (!format.empty() && format != "zstd")
      throw InputError(meta + ": compression_format '" + format + "' is not zstd (rosbag2's one compressor)");
    BagLayout layout;
    layout.zstd_messages = format == "zstd" && mode == "MESSAGE";
    const bool zstd_files = format == "zstd" && mode == "FILE";
    const YAML::Node files = info["relative_file_paths"];
    if (!files || !files.IsSequence() || files.size() == 0) throw InputError(meta + ": no relative_file_paths");
    for (const auto& f : files) {
      const std::string file = (fs::path(path) / f.as<std::string>()).string();
      if (!fs::exists(file, ec)) throw InputError(meta + ": its file " + file + " is missing");
      if (!fs::is_regular_file(file, ec))
        throw InputError(meta + ": its file " + file + " is not a regular file (a folder, FIFO or device)");
      layout.files.push_back({file, zstd_files});
    }
    return layout;
  } catch (const YAML::Exception& e) {
    throw InputError(meta + ": " + e.what());
  }
}

/// A temporary file removed when it goes out of scope.
struct TempFile {
  std::string path;
  ~TempFile() {
    std::error_code ec;
    if (!path.empty()) fs::remove(path, ec);
  }
};

/// The size of the file at `path` [bytes], 0 when it cannot be read (the budget is then the slack).
std::uint64_t file_bytes(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t n = fs::file_size(path, ec);
  return ec ? 0 : static_cast<std::uint64_t>(n);
}

/// Decompresses the zstd file `path` (compression_mode FILE) into a temporary file.
void unzstd_file(const std::string& path, TempFile& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be opened");
  out.path =
      (fs::temp_directory_path() / ("dyncal_bag_" + std::to_string(::getpid()) + "_" + fs::path(path).stem().string()))
          .string();
  std::ofstream o(out.path, std::ios::binary);
  if (!o) throw InputError(out.path + ": cannot be written");
  const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  std::vector<char> ibuf(ZSTD_DStreamInSize()), obuf(ZSTD_DStreamOutSize());
  DecompressionBudget budget(file_bytes(path), path);
  std::size_t last = 0;
  while (in) {
    in.read(ibuf.data(), static_cast<std::streamsize>(ibuf.size()));
    ZSTD_inBuffer input{ibuf.data(), static_cast<std::size_t>(in.gcount()), 0};
    while (input.pos < input.size) {
      ZSTD_outBuffer output{obuf.data(), obuf.size(), 0};
      last = ZSTD_decompressStream(ctx.get(), &output, &input);
      if (ZSTD_isError(last))
        throw InputError(path + ": does not decompress as zstd (" + ZSTD_getErrorName(last) + ")");
      budget.take(output.pos, path);  // the temporary file is bounded by the bag's size
      o.write(obuf.data(), static_cast<std::streamsize>(output.pos));
    }
  }
  if (last != 0) throw InputError(path + ": the zstd stream is truncated");
  if (!o) throw InputError(out.path + ": cannot be written");
}

/// Undoes compression_mode MESSAGE on one message's data, within the bag's decompression budget.
void unzstd_message(std::vector<std::uint8_t>& data, const std::string& where, DecompressionBudget& budget) {
  const unsigned long long size = ZSTD_getFrameContentSize(data.data(), data.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size > (1ull << 30))
    throw InputError(where + ": not a zstd frame (the bag's metadata says its messages are compressed)");
  budget.take(size, where);  // before the allocation: the bag's budget bounds every message's stated size
  std::vector<std::uint8_t> plain(static_cast<std::size_t>(size));
  const std::size_t got = ZSTD_decompress(plain.data(), plain.size(), data.data(), data.size());
  if (ZSTD_isError(got) || got != size) throw InputError(where + ": does not decompress as zstd");
  data.swap(plain);
}

BagMessages read_storage(const StorageFile& f, const KeepTopic& keep) {
  TempFile plain;
  std::string path = f.path;
  if (f.zstd) {
    unzstd_file(f.path, plain);
    path = plain.path;
  }
  const Storage s = storage_of_file(path);
  if (s == Storage::mcap) return read_mcap(path, keep);
  if (s == Storage::sqlite3) return read_sqlite_bag(path, keep);
  throw InputError(f.path + ": neither an MCAP nor a SQLite3 file (no magic at byte 0)");
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// "period 0.2000 ms, jitter 0.003 periods, 2 ticks without a sample" of strictly increasing stamps.
std::string clock_summary(const std::vector<std::int64_t>& ns) {
  Eigen::VectorXd t(static_cast<Eigen::Index>(ns.size()));
  for (std::size_t i = 0; i < ns.size(); ++i)
    t[static_cast<Eigen::Index>(i)] = static_cast<double>(ns[i] - ns[0]) * 1e-9;
  const SampleClock c = estimate_sample_clock(t, {{0, t.size()}}, median_step(t, {{0, t.size()}}));
  char s[160];
  std::snprintf(s, sizeof s, "period %.6g ms, stamp jitter %.3f periods RMS, %ld ticks without a sample",
                c.period * 1e3, c.stamp_jitter, c.missing);
  return s;
}

bool strictly_increasing(const std::vector<std::int64_t>& ns) {
  for (std::size_t i = 1; i < ns.size(); ++i)
    if (ns[i] <= ns[i - 1]) return false;
  return true;
}

/// The kept messages of every storage file of `layout`, their topics unified by name.
BagMessages merged_storage(const BagLayout& layout, const KeepTopic& keep) {
  std::vector<BagTopic> topics;
  std::vector<BagMessage> messages;
  for (const StorageFile& f : layout.files) {
    BagMessages part = read_storage(f, keep);
    std::vector<int> index;
    for (const BagTopic& t : part.topics) {
      const auto at = std::find_if(topics.begin(), topics.end(), [&](const BagTopic& x) { return x.name == t.name; });
      index.push_back(static_cast<int>(at - topics.begin()));
      if (at == topics.end()) topics.push_back(t);
    }
    for (BagMessage& m : part.messages) {
      m.topic = index[static_cast<std::size_t>(m.topic)];
      messages.push_back(std::move(m));
    }
  }
  BagMessages out;
  out.topics = std::move(topics);
  out.messages = std::move(messages);
  return out;
}

/// The JointState topic to read: options' --topic, checked, else the bag's only one; its index in
/// `topics` (its name into `topic`). Throws InputError naming the topics the bag has.
int chosen_topic(const std::string& path, const std::vector<BagTopic>& topics, std::string& topic) {
  const auto topic_named = [&](const std::string& name) {
    return std::find_if(topics.begin(), topics.end(), [&](const BagTopic& x) { return x.name == name; });
  };
  // The topic: --topic, else the one JointState topic.
  std::vector<std::string> joint_state_topics, all;
  for (const BagTopic& t : topics) {
    all.push_back(t.name + " (" + (t.type.empty() ? "no type" : t.type) + ")");
    if (t.type == kJointState) joint_state_topics.push_back(t.name);
  }
  if (topic.empty()) {
    if (joint_state_topics.empty())
      throw InputError(path + ": no " + kJointState + " topic; the bag has " +
                       (all.empty() ? "no topics" : joined(all)));
    if (joint_state_topics.size() > 1)
      throw InputError(path + ": " + std::to_string(joint_state_topics.size()) + " JointState topics (" +
                       joined(joint_state_topics) + "); choose one with --topic");
    topic = joint_state_topics.front();
  } else {
    const auto t = topic_named(topic);
    if (t == topics.end())
      throw InputError(path + ": no topic " + topic + "; the bag has " + (all.empty() ? "no topics" : joined(all)));
    if (t->type != kJointState)
      throw InputError(path + ": topic " + topic + " is " + (t->type.empty() ? "untyped" : t->type) + ", not a " +
                       kJointState);
  }
  const auto topic_at = topic_named(topic);
  if (topic_at->encoding != "cdr")
    throw InputError(path + ": topic " + topic + " is serialised as '" + topic_at->encoding + "', not cdr");
  return static_cast<int>(topic_at - topics.begin());
}

/// One JointState message's values of the robot's joints, with both its clocks [ns].
struct JointSample {
  std::int64_t header, log;
  std::vector<double> q, qd, tau;
};

/// A topic's messages decoded, the robot's joints matched by name.
struct DecodedTopic {
  std::vector<JointSample> samples;
  std::vector<std::string> ignored;     ///< joints of the messages that are not the robot's
  std::vector<std::string> last_names;  ///< the last message's joint names
  long without_robot = 0;               ///< messages without the robot's joints, skipped
  bool all_velocity = true, any_velocity = false;
};

/// Decodes the messages of topic `topic_index` (each message's data freed once read). Throws
/// InputError naming the message: not a JointState, some of the robot's joints missing, sizes that
/// differ.
DecodedTopic decode_topic(const std::string& path, const BagLayout& layout, std::vector<BagMessage>& messages,
                          int topic_index, const std::string& topic, const std::vector<std::string>& names) {
  std::uint64_t bag_bytes = 0;
  for (const StorageFile& f : layout.files) bag_bytes += file_bytes(f.path);
  DecompressionBudget message_budget(bag_bytes, path);
  const int n = static_cast<int>(names.size());
  DecodedTopic out;
  std::vector<JointSample>& samples = out.samples;
  std::vector<std::string>& ignored = out.ignored;
  std::vector<std::string>& last_names = out.last_names;
  long index = 0;
  JointStateMessage msg;
  std::string error;
  std::vector<int> column(static_cast<std::size_t>(n), -1);
  for (BagMessage& m : messages) {
    if (m.topic != topic_index) continue;
    ++index;
    const std::string where = path + ": " + topic + " message " + std::to_string(index);
    if (layout.zstd_messages) unzstd_message(m.data, where, message_budget);
    if (!decode_joint_state(m.data.data(), m.data.size(), msg, error))
      throw InputError(where + " is not a JointState: " + error);
    if (msg.name != last_names) {
      last_names = msg.name;
      std::vector<std::string> missing;
      for (int j = 0; j < n; ++j) {
        const auto at = std::find(msg.name.begin(), msg.name.end(), names[static_cast<std::size_t>(j)]);
        column[static_cast<std::size_t>(j)] = at == msg.name.end() ? -1 : static_cast<int>(at - msg.name.begin());
        if (at == msg.name.end()) missing.push_back(names[static_cast<std::size_t>(j)]);
      }
      if (static_cast<int>(missing.size()) < n && !missing.empty())
        throw InputError(where + " has joints " + joined(msg.name) + " but not the robot's " + joined(missing));
      for (const auto& name : msg.name)
        if (std::find(names.begin(), names.end(), name) == names.end() &&
            std::find(ignored.begin(), ignored.end(), name) == ignored.end() && static_cast<int>(missing.size()) < n)
          ignored.push_back(name);
    }
    if (column[0] < 0) {
      ++out.without_robot;
      continue;
    }
    const std::size_t k = msg.name.size();
    if (msg.position.size() != k || msg.effort.size() != k || (!msg.velocity.empty() && msg.velocity.size() != k))
      throw InputError(where + ": " + std::to_string(k) + " names but " + std::to_string(msg.position.size()) +
                       " positions, " + std::to_string(msg.velocity.size()) + " velocities, " +
                       std::to_string(msg.effort.size()) + " efforts (position and effort are needed for each)");
    if (msg.velocity.empty()) out.all_velocity = false;
    if (!msg.velocity.empty()) out.any_velocity = true;
    JointSample s{msg.stamp_ns(), m.log_time, {}, {}, {}};
    for (int j = 0; j < n; ++j) {
      const auto c = static_cast<std::size_t>(column[static_cast<std::size_t>(j)]);
      s.q.push_back(msg.position[c]);
      s.qd.push_back(msg.velocity.empty() ? 0.0 : msg.velocity[c]);
      s.tau.push_back(msg.effort[c]);
    }
    samples.push_back(std::move(s));
    m.data.clear();
    m.data.shrink_to_fit();
  }
  return out;
}

}  // namespace

bool is_ros2_bag(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return fs::is_regular_file(fs::path(path) / "metadata.yaml", ec);
  if (!fs::is_regular_file(path, ec)) return false;
  // Named as a bag's storage but without its magic: the real cause, not a CSV's "columns".
  const std::string ext = fs::path(path).extension().string();
  const Storage named = storage_of_file(path);
  if (ext == ".mcap" && named != Storage::mcap)
    throw InputError(path + ": named .mcap but not an MCAP file (no MCAP magic at byte 0: damaged, or not a bag)");
  if (ext == ".db3" && named != Storage::sqlite3)
    throw InputError(path + ": named .db3 but not a SQLite3 file (no SQLite magic at byte 0: damaged, or not a bag)");
  const Storage s = storage_of_file(path);
  return s == Storage::mcap || (s == Storage::sqlite3 && fs::path(path).extension() == ".db3");
}

BagLog read_ros2_bag_log(const std::string& path, const BagLogOptions& options) {
  const BagLayout layout = layout_of(path);
  const KeepTopic keep = [&](const BagTopic& t) {
    return t.type == kJointState && (options.topic.empty() || t.name == options.topic);
  };
  BagMessages bag = merged_storage(layout, keep);
  std::string topic = options.topic;
  const int topic_index = chosen_topic(path, bag.topics, topic);

  // Decode, and match the robot's joints by name.
  const auto& names = options.joint_names;
  const int n = static_cast<int>(names.size());
  DecodedTopic decoded = decode_topic(path, layout, bag.messages, topic_index, topic, names);
  std::vector<JointSample>& samples = decoded.samples;
  const long without_robot = decoded.without_robot;
  const bool all_velocity = decoded.all_velocity, any_velocity = decoded.any_velocity;
  const std::vector<std::string>& ignored = decoded.ignored;
  const std::vector<std::string>& last_names = decoded.last_names;
  if (samples.size() < 3)
    throw InputError(path + ": topic " + topic + " has " + std::to_string(samples.size()) +
                     " messages with the robot's joints (" + joined(names) + "); 3 or more are needed" +
                     (without_robot > 0 ? "; its joints are " + joined(last_names) : std::string()));

  // The clock: header stamps or log times, in its order.
  const bool header = options.clock == BagClock::header;
  bool stamps_set = false;
  for (const JointSample& s : samples) stamps_set = stamps_set || s.header != 0;
  if (header && !stamps_set)
    throw InputError(path + ": topic " + topic +
                     ": every header stamp is zero (the driver does not stamp); use --clock log");
  long reordered = 0;
  for (std::size_t i = 1; i < samples.size(); ++i)
    reordered += (header ? samples[i].header < samples[i - 1].header : samples[i].log < samples[i - 1].log) ? 1 : 0;
  std::stable_sort(samples.begin(), samples.end(), [&](const JointSample& a, const JointSample& b) {
    return header ? a.header < b.header : a.log < b.log;
  });
  std::vector<std::int64_t> header_ns, log_ns;
  for (const JointSample& s : samples) {
    header_ns.push_back(s.header);
    log_ns.push_back(s.log);
  }
  const std::vector<std::int64_t>& clock = header ? header_ns : log_ns;
  for (std::size_t i = 1; i < clock.size(); ++i)
    if (clock[i] == clock[i - 1])
      throw InputError(path + ": topic " + topic + ": two messages have the same " +
                       (header ? "header stamp" : "log time") + " (" + std::to_string(clock[i] / 1000000000) + " s " +
                       std::to_string(clock[i] % 1000000000) + " ns; sample " + std::to_string(i + 1) +
                       " in time order)" + (header ? "; --clock log takes the recorder's times" : ""));

  BagLog out;
  JointLog& log = out.log;
  const auto rows = static_cast<Eigen::Index>(samples.size());
  log.t.resize(rows);
  log.q.resize(rows, n);
  log.qd.resize(rows, n);
  log.qdd = Eigen::MatrixXd::Zero(rows, n);
  log.tau.resize(rows, n);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const JointSample& s = samples[static_cast<std::size_t>(i)];
    log.t[i] = static_cast<double>(clock[static_cast<std::size_t>(i)] - clock[0]) * 1e-9;
    for (int j = 0; j < n; ++j) {
      log.q(i, j) = s.q[static_cast<std::size_t>(j)];
      log.qd(i, j) = s.qd[static_cast<std::size_t>(j)];
      log.tau(i, j) = s.tau[static_cast<std::size_t>(j)];
    }
  }
  log.has_qd = all_velocity;
  if (!all_velocity) log.qd.setZero();
  log.source = path;
  for (Eigen::Index i = 0; i < rows; ++i)
    for (int j = 0; j < n; ++j)
      if (!std::isfinite(log.q(i, j)) || !std::isfinite(log.tau(i, j)) || !std::isfinite(log.qd(i, j)))
        throw InputError(path + ": topic " + topic + ": sample " + std::to_string(i + 1) + ", joint " +
                         std::to_string(j + 1) + " (" + names[static_cast<std::size_t>(j)] +
                         "): a value is NaN or infinite");
  check_log_time(log.t, path);

  out.notes.push_back(
      path + ": topic " + topic + ", " + std::to_string(rows) + " JointState samples, joints " + joined(names) +
      " matched by name" + (ignored.empty() ? std::string() : "; ignored: " + joined(ignored)) +
      (without_robot > 0 ? "; " + std::to_string(without_robot) + " messages without them skipped" : std::string()) +
      (all_velocity   ? ""
       : any_velocity ? "; velocity missing from some messages: computed from position"
                      : "; no velocity in the messages: computed from position"));
  const std::string header_clock = !stamps_set                      ? "not set"
                                   : strictly_increasing(header_ns) ? clock_summary(header_ns)
                                                                    : "not increasing";
  const std::string log_clock = strictly_increasing(log_ns) ? clock_summary(log_ns) : "not increasing";
  out.notes.push_back(path + ": clock " + (header ? "header stamps" : "log times") + " (--clock)" +
                      (reordered > 0 ? ", " + std::to_string(reordered) + " messages recorded out of its order" : "") +
                      "; header stamps: " + header_clock + "; log times: " + log_clock);
  return out;
}

}  // namespace dyncal::host
