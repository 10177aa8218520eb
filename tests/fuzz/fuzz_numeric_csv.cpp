// libFuzzer target: the CSV reader (host_sim/logs/src/numeric_csv.cpp) on any text. Bad
// input must end in InputError with a message; anything else (a crash, another exception, an
// out-of-bounds access, undefined behaviour) is a finding. A parsed table must be consistent.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/numeric_csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    const auto csv = dyncal::host::parse_numeric_csv(in, "fuzz.csv");
    if (static_cast<std::size_t>(csv.values.cols()) != csv.header.size() && csv.values.rows() > 0) std::abort();
    if (!csv.values.allFinite()) std::abort();
  } catch (const dyncal::host::InputError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}
