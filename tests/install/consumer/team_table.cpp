// A team's tool on the installed access library: its item table from its own
// generated files (canhil::rtdb_access).
#include <cstdio>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/database.hpp"

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  try {
    const auto table = canhil::rtdb::ItemTable::from_files(argv[1], argv[2]);
    std::printf("team_table: %d agents, CMD_VEL id %d, %zu bytes\n", table.agent_count(),
                table.id("CMD_VEL").value_or(-1), table.size(table.id("CMD_VEL").value_or(-1)).value_or(0));
  } catch (const canhil::SetupError& e) {
    std::printf("team_table: %s\n", e.what());
    return 1;
  }
  return 0;
}
