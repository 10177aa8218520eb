// libFuzzer target: the drive's Modbus TCP framing (lib/include/dyncal/drive/modbus_frames.hpp) on any byte
// stream. Splits the input into frames as the drive does and checks what the server relies on: a
// complete frame lies inside the buffer and is at least header + function code long, an invalid
// length is reported as such, and the PDU check reads only its own bytes (ASan catches the rest).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "dyncal/drive/modbus_frames.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using dyncal::drive::MbapFrame;
  std::size_t used = 0;
  while (used < size) {
    // An exact-size copy: any read past the frame's end is a heap overflow ASan reports.
    const std::vector<std::uint8_t> rest(data + used, data + size);
    const MbapFrame f = dyncal::drive::next_mbap_frame(rest.data(), rest.size());
    if (f.status != MbapFrame::Status::complete) break;
    if (f.bytes < dyncal::drive::kMbapHeaderBytes + 1 || f.bytes > rest.size() ||
        f.bytes > dyncal::drive::kMaxTcpAduBytes)
      std::abort();
    const std::vector<std::uint8_t> pdu(rest.begin() + dyncal::drive::kMbapHeaderBytes, rest.begin() + f.bytes);
    (void)dyncal::drive::request_pdu_consistent(pdu.data(), pdu.size());
    used += f.bytes;
  }
  return 0;
}
