// The build's absolute paths for the tests (test_paths.hpp): the only test unit compiled with them.
#include "support/test_paths.hpp"

namespace dyncal::test {

const char* source_dir() noexcept {
  return DYNCAL_SOURCE_DIR;
}
const char* dyncal_binary() noexcept {
  return DYNCAL_BINARY;
}
const char* tx40_data() noexcept {
  return DYNCAL_TX40_DATA;
}

}  // namespace dyncal::test
