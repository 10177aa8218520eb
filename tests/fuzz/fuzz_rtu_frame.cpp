// libFuzzer target: the drive's Modbus RTU request framing (lib/include/dyncal/drive/modbus_frames.hpp)
// on any byte stream. Splits the input into requests as an RTU receiver does and checks what a
// server relies on: a complete frame lies inside the buffer, is 4..256 bytes, and its CRC verdict is
// crc16 of its bytes; a function whose length is unknown or an impossible length is reported as such
// (the receiver then drops one byte and resynchronises, standing for the line's silence). Every read
// is from an exact-size copy, so a read past a frame's end is a heap overflow ASan reports.
// Then the same bytes through the drive's line receiver (rtu_receiver.hpp), in chunks whose sizes
// and gaps the input's own bytes choose: every request it hands over is for its address, 4..256
// bytes, with a right CRC, and it never holds more than its capacity.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/rtu_receiver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using dyncal::drive::RtuFrame;
  std::size_t used = 0;
  while (used < size) {
    const std::vector<std::uint8_t> rest(data + used, data + size);
    const RtuFrame f = dyncal::drive::next_rtu_request(rest.data(), rest.size());
    if (f.status == RtuFrame::Status::incomplete) break;
    if (f.status != RtuFrame::Status::complete) {
      used += 1;
      continue;
    }
    if (f.bytes < 4 || f.bytes > rest.size() || f.bytes > dyncal::drive::kMaxRtuAduBytes) std::abort();
    const std::vector<std::uint8_t> frame(rest.begin(), rest.begin() + static_cast<std::ptrdiff_t>(f.bytes));
    const std::uint16_t crc = dyncal::drive::crc16(frame.data(), frame.size() - 2);
    if (f.crc_ok != (frame[frame.size() - 2] == (crc & 0xFF) && frame[frame.size() - 1] == (crc >> 8))) std::abort();
    const std::vector<std::uint8_t> pdu(frame.begin() + 1, frame.end() - 2);
    (void)dyncal::drive::request_pdu_consistent(pdu.data(), pdu.size());
    used += f.bytes;
  }

  dyncal::drive::RtuReceiver<> line(1, 50000);
  std::uint64_t now = 0;
  auto answer = [](const std::uint8_t* adu, std::size_t n) {
    if (n < 4 || n > dyncal::drive::kMaxRtuAduBytes || adu[0] != 1) std::abort();
    const std::vector<std::uint8_t> frame(adu, adu + n);
    const std::uint16_t crc = dyncal::drive::crc16(frame.data(), n - 2);
    if (frame[n - 2] != (crc & 0xFF) || frame[n - 1] != (crc >> 8)) std::abort();
  };
  for (std::size_t k = 0; k < size;) {
    const std::size_t chunk = 1 + data[k] % 64;  // a read's size
    const std::size_t n = chunk < size - k ? chunk : size - k;
    now += (data[k] & 0x80) ? 60000 : 100;  // a silence longer than the resync, or a short gap
    line.push(data + k, n, now);
    line.poll(now, answer);
    if (line.pending() > 2 * dyncal::drive::kMaxRtuAduBytes) std::abort();
    k += n;
  }
  line.poll(now + 60000, answer);
  return 0;
}
