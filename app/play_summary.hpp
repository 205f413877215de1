// app/play_summary.hpp — what a run's play came to, for its end summary
// (`canhil run` in virtual time, in virtual time with --external): the goals,
// with the team that scored when two play, and the referee's calls and score.
#pragma once

#include <cstdio>

#include "canhil/emulator/session.hpp"

namespace canhil::app {

/// The goals ("  GOAL at T s in the +x goal, for TEAM") and, when the session
/// has a referee, its score and every call with its virtual time, onto `out`.
void print_play(const emulator::Session& session, FILE* out);

}  // namespace canhil::app
