#pragma once
// Where a test finds the source tree, the dyncal program it runs and the real TX40 log: absolute
// paths of this build, defined in test_paths.cpp, the one test source compiled with them. Every other
// test unit's compile line is then the same in any clone folder, so ccache serves a clean clone in a
// new folder (CI) instead of recompiling every test program.

namespace dyncal::test {

/// The source tree's root, absolute, without a trailing '/' (e.g. "/work/dyncal").
const char* source_dir() noexcept;
/// The dyncal program with the test robots compiled in (target dyncal_test_cli), absolute.
const char* dyncal_binary() noexcept;
/// The folder of the real Staubli TX40 log (tests/data/staubli_tx40), absolute.
const char* tx40_data() noexcept;

}  // namespace dyncal::test
