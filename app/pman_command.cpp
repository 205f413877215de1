// `canhil pman list`: every robot's PMan table as it is now — the tables a
// running canhil run (or any master with CAMBADA's table layout, the team's
// own PMan included) created at keys 0x9011 + 2 x agent, read without
// attaching: each registered process, its pid once attached, its state and
// its activations.
#include <cstdio>

#include "canhil/pman/masters.hpp"
#include "commands.hpp"

namespace canhil::app {
namespace {

const char* state_name(const pman::Process& p) {
  if (p.pid == 0) return "not attached";
  if (p.idle()) return "waiting for its next activation";
  return "activated, in its cycle";
}

}  // namespace

int run_pman(Args& args) {
  const std::vector<std::string> words = args.positionals();
  if (words.size() != 2 || words[1] != "list") throw UsageError("pman takes one word: list");
  const std::vector<pman::TableView> tables = pman::read_tables();
  if (tables.empty()) {
    std::printf(
        "no PMan table (keys 0x9011 + 2 x agent, the second team's 0x9111 + 2 x agent, agents 1..6): no canhil run "
        "with PMan, and no other master\n");
    return 0;
  }
  for (const pman::TableView& t : tables) {
    std::printf("%sagent %d: table at key 0x%x, %llu ticks\n", t.set == 0 ? "" : "second team, ", t.agent,
                static_cast<unsigned>(t.key), static_cast<unsigned long long>(t.ticks));
    for (const pman::Process& p : t.processes) {
      std::printf("  %-16s pid %-7d %-32s %llu activations\n", p.name.c_str(), p.pid, state_name(p),
                  static_cast<unsigned long long>(p.activations));
    }
  }
  return 0;
}

}  // namespace canhil::app
