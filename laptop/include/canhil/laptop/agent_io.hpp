// canhil/laptop/agent_io.hpp — the reference agent's RTDB side: what it reads
// before deciding (VISION_INFO, CMD_POS, CMD_GRABBER_INFO, and the base
// station's COACH_INFO in its own database) and what it writes
// after (CMD_VEL, CMD_GRABBER, and CMD_KICKER once per kick), for one agent.
// Used by canhil-agent (its own agent) and by the virtual-time run (each
// robot's agent in one process). DB_init or DB_init_all first. It works in one
// memory space: the agent's number in the first team's set, N + it in the
// second's (DB_space() for a process's own).
#pragma once

#include "canhil/laptop/agent.hpp"
#include "canhil/rtdb/cambada_types.h"

namespace canhil::laptop {

class AgentIo {
 public:
  explicit AgentIo(int space) : space_(space) {}
  /// The inputs as the agent's database holds them now; `dt_s` since the last decision.
  AgentInput read(double dt_s);
  void write(const AgentOutput& out);

 private:
  int space_;
};

}  // namespace canhil::laptop
