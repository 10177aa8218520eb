// The source tree's path (source_tree.hpp): DYNCAL_SOURCE_DIR, defined for this file alone.
#include "dyncal_host/common/source_tree.hpp"

namespace dyncal::host {

std::string source_tree_dir() {
  return DYNCAL_SOURCE_DIR;
}

}  // namespace dyncal::host
