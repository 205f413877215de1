// canhil-rtdb-gen CONFIG OUT_DIR — writes OUT_DIR/rtdb_user.h and
// OUT_DIR/rtdb_config.c from an RTDB configuration file. Exit 2 with
// FILE:LINE: reason on a mistake.
#include <cstdio>
#include <fstream>

#include "canhil/rtdb/config_file.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: canhil-rtdb-gen CONFIG OUT_DIR\n");
    return 2;
  }
  try {
    const auto config = canhil::rtdb::load_rtdb_config(argv[1]);
    const std::filesystem::path out(argv[2]);
    std::filesystem::create_directories(out);
    std::ofstream(out / "rtdb_user.h") << canhil::rtdb::generate_user_header(config);
    std::ofstream(out / "rtdb_config.c") << canhil::rtdb::generate_config_source(config);
    return 0;
  } catch (const canhil::rtdb::RtdbConfigError& e) {
    std::fprintf(stderr, "canhil-rtdb-gen: %s\n", e.what());
    return 2;
  }
}
