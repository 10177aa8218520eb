#include "dyncal_host/logs/mcap_reader.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/decompression_budget.hpp"

namespace dyncal::host {
namespace {

constexpr unsigned char kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kDataEnd = 0x0F,
};

std::string record_name(std::uint8_t op) {
  static const char* names[] = {"",           "Header",        "Footer",          "Schema",
                                "Channel",    "Message",       "Chunk",           "MessageIndex",
                                "ChunkIndex", "Attachment",    "AttachmentIndex", "Statistics",
                                "Metadata",   "MetadataIndex", "SummaryOffset",   "DataEnd"};
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", op);
  return op >= 1 && op <= 0x0F ? std::string(names[op]) + " (" + hex + ")" : std::string("record ") + hex;
}

/// A record's body with bounds-checked little-endian fields; errors name the record and its offset.
class Fields {
 public:
  Fields(const std::uint8_t* p, std::size_t n, std::string where) : p_(p), n_(n), where_(std::move(where)) {}
  std::uint64_t u(int bytes) {
    need(static_cast<std::size_t>(bytes));
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(p_[at_ + static_cast<std::size_t>(i)]) << (8 * i);
    at_ += static_cast<std::size_t>(bytes);
    return v;
  }
  std::string string() {
    const std::size_t len = u(4);
    need(len);
    std::string s(reinterpret_cast<const char*>(p_ + at_), len);
    at_ += len;
    return s;
  }
  /// A u32-length-prefixed byte array or map, skipped.
  void skip_prefixed(int len_bytes) {
    const std::size_t len = u(len_bytes);
    need(len);
    at_ += len;
  }
  const std::uint8_t* rest() const { return p_ + at_; }
  std::size_t left() const { return n_ - at_; }
  void skip(std::size_t len) {
    need(len);
    at_ += len;
  }

 private:
  void need(std::size_t len) const {
    if (len > n_ - at_) throw InputError(where_ + ": a field runs past the record's end");
  }
  const std::uint8_t* p_;
  std::size_t n_, at_ = 0;
  std::string where_;
};

class Parser {
 public:
  Parser(std::string name, const KeepTopic& keep) : name_(std::move(name)), keep_(keep) {}

  void parse(std::istream& in) {
    unsigned char magic[8];
    if (!in.read(reinterpret_cast<char*>(magic), 8) || std::memcmp(magic, kMagic, 8) != 0)
      throw InputError(name_ + ": not an MCAP file (no MCAP magic at byte 0)");
    in.seekg(0, std::ios::end);
    file_end_ = in.tellg();
    budget_ = DecompressionBudget(static_cast<std::uint64_t>(std::max<std::streamoff>(0, file_end_)), name_);
    in.seekg(8);
    // The data section's CRC-32 runs over every byte before the DataEnd record, magic included.
    std::uint32_t data_crc = static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0));
    data_crc = static_cast<std::uint32_t>(::crc32(data_crc, magic, 8));
    bool data_end = false;
    std::uint64_t offset = 8;
    std::vector<std::uint8_t> body;
    for (;;) {
      unsigned char head[9];
      in.read(reinterpret_cast<char*>(head), 9);
      if (in.gcount() == 0)
        throw InputError(name_ + ": truncated at byte " + std::to_string(offset) +
                         ": the file ends without a Footer (a recording cut off before it closed the file)");
      if (in.gcount() != 9)
        throw InputError(name_ + ": truncated at byte " + std::to_string(offset) + ": a record header is cut off");
      const std::uint8_t op = head[0];
      std::uint64_t len = 0;
      for (int i = 0; i < 8; ++i) len |= static_cast<std::uint64_t>(head[1 + i]) << (8 * i);
      const std::string where = name_ + ": byte " + std::to_string(offset) + ", " + record_name(op);
      if (op == kFooter) {
        if (len != 20) throw InputError(where + ": length " + std::to_string(len) + ", not 20");
        read_body(in, len, where, body);
        unsigned char tail[8];
        if (!in.read(reinterpret_cast<char*>(tail), 8) || std::memcmp(tail, kMagic, 8) != 0)
          throw InputError(where + ": no MCAP magic after the Footer (truncated or corrupt)");
        return;
      }
      if (data_end) {
        skip_body(in, len, where);  // the summary section: not needed for a full read
      } else {
        read_body(in, len, where, body);
        if (op == kDataEnd) {
          Fields f(body.data(), body.size(), where);
          const auto stated = static_cast<std::uint32_t>(f.u(4));
          if (stated != 0 && stated != data_crc)
            throw InputError(where + ": the data section's CRC-32 is " + hex(data_crc) + ", DataEnd states " +
                             hex(stated) + " (the file is corrupt)");
          data_end = true;
        } else {
          data_crc = static_cast<std::uint32_t>(::crc32(data_crc, head, 9));
          data_crc = crc_of(data_crc, body);
          if (op == kSchema) schema(body.data(), body.size(), where);
          if (op == kChannel) channel(body.data(), body.size(), where);
          if (op == kMessage) message(body.data(), body.size(), where);
          if (op == kChunk) chunk(body, where);
        }
      }
      offset += 9 + len;
    }
  }

  BagMessages result;

 private:
  static std::string hex(std::uint32_t v) {
    char s[16];
    std::snprintf(s, sizeof s, "0x%08X", v);
    return s;
  }
  static std::uint32_t crc_of(std::uint32_t crc, const std::vector<std::uint8_t>& b) {
    // zlib's crc32 takes a uInt length; records above 4 GiB are fed in pieces.
    std::size_t at = 0;
    while (at < b.size()) {
      const std::size_t n = std::min<std::size_t>(b.size() - at, 1u << 30);
      crc = static_cast<std::uint32_t>(::crc32(crc, b.data() + at, static_cast<uInt>(n)));
      at += n;
    }
    return crc;
  }

  /// Bytes left in the file after the stream's position.
  std::uint64_t left_in_file(std::istream& in) const {
    const auto here = in.tellg();
    return here < 0 || file_end_ < here ? 0 : static_cast<std::uint64_t>(file_end_ - here);
  }

  void read_body(std::istream& in, std::uint64_t len, const std::string& where, std::vector<std::uint8_t>& body) {
    // A record claiming more than the file holds is truncation, found before allocating it.
    const std::uint64_t left = left_in_file(in);
    if (len > left)
      throw InputError(where + ": " + std::to_string(len) + " bytes stated, " + std::to_string(left) +
                       " left in the file (truncated)");
    body.resize(static_cast<std::size_t>(len));
    if (len > 0 && !in.read(reinterpret_cast<char*>(body.data()), static_cast<std::streamsize>(len)))
      throw InputError(where + ": cannot be read");
  }

  void skip_body(std::istream& in, std::uint64_t len, const std::string& where) {
    const std::uint64_t left = left_in_file(in);
    if (len > left)
      throw InputError(where + ": " + std::to_string(len) + " bytes stated, " + std::to_string(left) +
                       " left in the file (truncated)");
    in.seekg(static_cast<std::streamoff>(len), std::ios::cur);
  }

  void schema(const std::uint8_t* p, std::size_t n, const std::string& where) {
    Fields f(p, n, where);
    const auto id = static_cast<std::uint16_t>(f.u(2));
    const std::string type = f.string();
    (void)f.string();  // encoding (ros2msg)
    f.skip_prefixed(4);
    schemas_[id] = type;
  }

  void channel(const std::uint8_t* p, std::size_t n, const std::string& where) {
    Fields f(p, n, where);
    const auto id = static_cast<std::uint16_t>(f.u(2));
    const auto schema_id = static_cast<std::uint16_t>(f.u(2));
    BagTopic t;
    t.name = f.string();
    t.encoding = f.string();
    f.skip_prefixed(4);  // metadata map
    if (schema_id != 0) {
      const auto s = schemas_.find(schema_id);
      if (s == schemas_.end())
        throw InputError(where + ": channel " + std::to_string(id) + " (" + t.name + ") names schema " +
                         std::to_string(schema_id) + ", which no Schema record declared before it");
      t.type = s->second;
    }
    if (channels_.count(id)) return;  // repeated (each chunk may repeat its channels)
    const int index = static_cast<int>(result.topics.size());
    result.topics.push_back(t);
    channels_[id] = keep_(t) ? index : -1 - index;
  }

  void message(const std::uint8_t* p, std::size_t n, const std::string& where) {
    Fields f(p, n, where);
    const auto id = static_cast<std::uint16_t>(f.u(2));
    f.skip(4);  // sequence
    const std::uint64_t log_time = f.u(8);
    f.skip(8);  // publish time
    const auto c = channels_.find(id);
    if (c == channels_.end())
      throw InputError(where + ": a message on channel " + std::to_string(id) + ", which no Channel record declared");
    if (c->second < 0) return;
    BagMessage m;
    m.topic = c->second;
    m.log_time = static_cast<std::int64_t>(log_time);
    m.data.assign(f.rest(), f.rest() + f.left());
    result.messages.push_back(std::move(m));
  }

  void chunk(const std::vector<std::uint8_t>& body, const std::string& where) {
    Fields f(body.data(), body.size(), where);
    f.skip(16);  // message start and end time
    const std::uint64_t size = f.u(8);
    const auto crc = static_cast<std::uint32_t>(f.u(4));
    const std::string compression = f.string();
    const std::uint64_t stored = f.u(8);
    if (stored > f.left()) throw InputError(where + ": its records run past the chunk's end");
    const std::uint8_t* src = f.rest();
    std::vector<std::uint8_t> plain;
    if (compression.empty()) {
      if (stored != size)
        throw InputError(where + ": uncompressed, " + std::to_string(stored) + " bytes stored but " +
                         std::to_string(size) + " stated");
      plain.assign(src, src + stored);
    } else if (compression == "zstd" || compression == "lz4") {
      budget_.check(size, where);  // a stated size beyond the file's budget: refused before any allocation
      // Streamed into a buffer that grows with what actually decompresses (never more than the stated
      // size), so that a chunk stating a huge size allocates nothing it does not fill.
      const bool zstd = compression == "zstd";
      const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> zctx(zstd ? ZSTD_createDCtx() : nullptr,
                                                                      &ZSTD_freeDCtx);
      LZ4F_dctx* lctx_raw = nullptr;
      if (!zstd && LZ4F_isError(LZ4F_createDecompressionContext(&lctx_raw, LZ4F_VERSION)))
        throw InputError(where + ": no lz4 context");
      const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> lctx(lctx_raw,
                                                                                      &LZ4F_freeDecompressionContext);
      plain.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1 << 16)));
      std::size_t out_at = 0, in_at = 0;
      for (;;) {
        if (out_at == plain.size() && plain.size() < size)
          plain.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size, 2 * plain.size())));
        std::size_t out_n = plain.size() - out_at, in_n = static_cast<std::size_t>(stored) - in_at, hint = 0;
        if (zstd) {
          ZSTD_inBuffer input{src, static_cast<std::size_t>(stored), in_at};
          ZSTD_outBuffer output{plain.data(), plain.size(), out_at};
          hint = ZSTD_decompressStream(zctx.get(), &output, &input);
          if (ZSTD_isError(hint))
            throw InputError(where + ": the zstd chunk does not decompress (" + ZSTD_getErrorName(hint) + ")");
          out_n = output.pos - out_at;
          in_n = input.pos - in_at;
        } else {
          hint = LZ4F_decompress(lctx.get(), plain.data() + out_at, &out_n, src + in_at, &in_n, nullptr);
          if (LZ4F_isError(hint))
            throw InputError(where + ": the lz4 chunk does not decompress (" + LZ4F_getErrorName(hint) + ")");
        }
        out_at += out_n;
        in_at += in_n;
        if (hint == 0) break;  // the frame is complete
        if (in_n == 0 && out_n == 0)
          throw InputError(where + ": the " + compression + " chunk ends before its " + std::to_string(size) +
                           " bytes (truncated or corrupt)");
      }
      budget_.take(out_at, where);
      if (out_at != size)
        throw InputError(where + ": the " + compression + " chunk decompresses to " + std::to_string(out_at) +
                         " bytes, not its stated " + std::to_string(size));
      plain.resize(out_at);
    } else {
      throw InputError(where + ": compression '" + compression + "' is not one of none, zstd, lz4");
    }
    if (crc != 0 && crc_of(static_cast<std::uint32_t>(::crc32(0L, Z_NULL, 0)), plain) != crc)
      throw InputError(where + ": the chunk's CRC-32 does not match its records (the file is corrupt)");
    // The chunk's records: Schema, Channel and Message.
    std::size_t at = 0;
    while (at < plain.size()) {
      if (plain.size() - at < 9) throw InputError(where + ": a record header is cut off inside the chunk");
      const std::uint8_t op = plain[at];
      std::uint64_t len = 0;
      for (int i = 0; i < 8; ++i)
        len |= static_cast<std::uint64_t>(plain[at + 1 + static_cast<std::size_t>(i)]) << (8 * i);
      const std::string inner = where + ", record " + std::to_string(at) + " bytes in, " + record_name(op);
      if (len > plain.size() - at - 9) throw InputError(inner + ": runs past the chunk's end");
      const std::uint8_t* p = plain.data() + at + 9;
      if (op == kSchema) schema(p, static_cast<std::size_t>(len), inner);
      if (op == kChannel) channel(p, static_cast<std::size_t>(len), inner);
      if (op == kMessage) message(p, static_cast<std::size_t>(len), inner);
      at += 9 + static_cast<std::size_t>(len);
    }
  }

  std::string name_;
  const KeepTopic& keep_;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, int> channels_;  ///< channel id -> topic index, or -1 - index when not kept
  std::streampos file_end_ = 0;
  DecompressionBudget budget_{0, ""};  ///< what the chunks may decompress to, from the file's size
};

}  // namespace

BagMessages parse_mcap(std::istream& in, const std::string& name, const KeepTopic& keep) {
  Parser p(name, keep);
  p.parse(in);
  return std::move(p.result);
}

BagMessages read_mcap(const std::string& path, const KeepTopic& keep) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot be opened");
  return parse_mcap(in, path, keep);
}

}  // namespace dyncal::host
