// libFuzzer target: the MCAP reader (host_sim/logs/src/mcap_reader.cpp) and the
// JointState CDR decoder (joint_state_cdr.cpp) on any bytes. Bad input must end in InputError with a
// message (the reader) or false with an error (the decoder); anything else (a crash, another
// exception, an out-of-bounds access, undefined behaviour, a huge allocation) is a finding.
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/joint_state_cdr.hpp"
#include "dyncal_host/logs/mcap_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  dyncal::host::JointStateMessage msg;
  std::string error;
  // The bytes as a CDR JointState on their own too.
  if (!dyncal::host::decode_joint_state(data, size, msg, error) && error.empty()) std::abort();
  try {
    const auto bag = dyncal::host::parse_mcap(in, "fuzz.mcap", [](const dyncal::host::BagTopic&) { return true; });
    for (const auto& m : bag.messages) {
      if (m.topic < 0 || static_cast<std::size_t>(m.topic) >= bag.topics.size()) std::abort();
      error.clear();
      if (!dyncal::host::decode_joint_state(m.data.data(), m.data.size(), msg, error) && error.empty()) std::abort();
    }
  } catch (const dyncal::host::InputError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}
