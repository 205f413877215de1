// tests/support/test_paths.hpp — where the tests find shipped files and binaries.
// The paths are absolute and differ from one checkout to the next, so they live
// in one generated unit (test_paths.cpp in the build tree, made by
// tests/CMakeLists.txt) instead of a macro in every test: a second clone of
// the same commit then compiles the tests to the same objects, and a compiler
// cache shares them.
#pragma once

#include <string>

namespace canhil::test {
/// The checkout's root (the folder with frames/, emulator/, ...).
std::string source_dir();
/// The build tree's root.
std::string build_dir();
/// The `canhil` program of this build.
std::string canhil_binary();
/// The user-space bus's preload, libcanhil-bus.so, of this build.
std::string bus_preload();
/// The lockstep time shim, libcanhil-timeshim.so, of this build.
std::string time_shim();
/// frames/canhil.dbc in the checkout.
inline std::string shipped_dbc() { return source_dir() + "/frames/canhil.dbc"; }
}  // namespace canhil::test
