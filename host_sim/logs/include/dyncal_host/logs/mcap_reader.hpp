#pragma once
// The records of an MCAP file (https://mcap.dev/spec, version 0), rosbag2's default storage since
// Iron: the data section is read in order, record by record; Chunk records are decompressed (none,
// zstd or lz4 frame, through Debian's libzstd and liblz4) and their CRC-32 checked; Schema and
// Channel records give the topics; Message records of kept topics are copied. The summary section
// is not needed for a full read and is skipped; DataEnd's CRC of the data section is checked.

#include <istream>
#include <string>

#include "dyncal_host/logs/bag_messages.hpp"

namespace dyncal::host {

/// Reads the MCAP file at `path` (see parse_mcap). Throws InputError when it cannot be opened.
BagMessages read_mcap(const std::string& path, const KeepTopic& keep);

/// Parses MCAP bytes from `in`; `name` stands for the file in messages. A topic is a Channel with
/// its Schema's name as type (schema 0: no type) and the channel's message encoding. Throws
/// InputError on one line naming `name`, the byte offset and the record: no MCAP magic, a record
/// running past the end (a truncated file: a recording killed before it closed the file), a
/// field running past its record, an unknown compression, a chunk that does not decompress to its
/// stated size or CRC, a message on an undeclared channel, a data-section CRC mismatch, no Footer.
BagMessages parse_mcap(std::istream& in, const std::string& name, const KeepTopic& keep);

}  // namespace dyncal::host
