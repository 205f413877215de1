// tests/support/test_paths.hpp — where the tests find shipped files and binaries.
#pragma once

#include <string>

namespace canhil::test {
inline std::string shipped_dbc() { return CANHIL_TEST_SOURCE_DIR "/frames/canhil.dbc"; }
inline std::string source_dir() { return CANHIL_TEST_SOURCE_DIR; }
inline std::string canhil_binary() { return CANHIL_TEST_CANHIL_BINARY; }
inline std::string build_dir() { return CANHIL_TEST_BUILD_DIR; }
}  // namespace canhil::test
