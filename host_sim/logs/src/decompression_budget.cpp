#include "dyncal_host/logs/decompression_budget.hpp"

#include <algorithm>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

DecompressionBudget::DecompressionBudget(std::uint64_t file_bytes, std::string file)
    : file_bytes_(file_bytes), file_(std::move(file)) {
  const std::uint64_t scaled =
      file_bytes > kMaxBytes / kMaxExpansion ? kMaxBytes : file_bytes * kMaxExpansion + kSlackBytes;
  limit_ = std::min(scaled, kMaxBytes);
}

void DecompressionBudget::check(std::uint64_t n, const std::string& where) const {
  if (n > remaining())
    throw InputError(where + ": decompresses to more than the " + std::to_string(limit_) + " bytes a " +
                     std::to_string(file_bytes_) + "-byte file may hold (" + std::to_string(kMaxExpansion) +
                     " times its size plus 16 MiB, at most 4 GiB: a decompression bomb or a corrupt file)");
}

void DecompressionBudget::take(std::uint64_t n, const std::string& where) {
  check(n, where);
  used_ += n;
}

}  // namespace dyncal::host
