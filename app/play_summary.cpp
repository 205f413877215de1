// `canhil run`'s goals and referee calls (play_summary.hpp).
#include "play_summary.hpp"

#include "canhil/emulator/referee.hpp"

namespace canhil::app {

void print_play(const emulator::Session& session, FILE* out) {
  const auto& teams = session.scenario().teams;
  for (const emulator::Goal& g : session.goals()) {
    if (teams.size() == 1) {
      std::fprintf(out, "  GOAL at %.2f s in the %s goal\n", to_seconds(g.time),
                   g.positive_x ? "+x (opponent)" : "-x (own)");
      continue;
    }
    const std::size_t scorer = teams[0].attacks_positive_x == g.positive_x ? 0 : 1;
    std::fprintf(out, "  GOAL at %.2f s in the %s goal, for %s\n", to_seconds(g.time), g.positive_x ? "+x" : "-x",
                 teams[scorer].name.c_str());
  }
  const emulator::Referee* referee = session.referee();
  if (referee == nullptr) return;
  std::fprintf(out, "  referee: %zu call(s)", referee->calls().size());
  for (std::size_t t = 0; t < teams.size(); ++t) {
    std::fprintf(out, "%s %s %d", t == 0 ? ", score" : " :", teams[t].name.c_str(), referee->score()[t]);
  }
  std::fprintf(out, "\n");
  for (const emulator::RefereeCall& c : referee->calls()) {
    std::fprintf(out, "    %7.2f s  %s\n", to_seconds(c.time), c.text.c_str());
  }
}

}  // namespace canhil::app
