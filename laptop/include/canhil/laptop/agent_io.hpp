// canhil/laptop/agent_io.hpp — the reference agent's RTDB side: what it reads
// before deciding (VISION_INFO's balls, CMD_POS, CMD_GRABBER_INFO, and the
// base station's COACH_INFO in its own database, else its own copy) and what
// it writes after (CMD_VEL, CMD_GRABBER, and CMD_KICKER once per kick), for
// one agent, through an rtdb::Database in a layout (canhil's RTDB in canhil's
// layout, or a team's library in the team's). Used by canhil-agent (its own
// agent) and by the virtual-time run (each robot's agent in one process).
#pragma once

#include <memory>

#include "canhil/laptop/agent.hpp"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"

namespace canhil::laptop {

class AgentIo {
 public:
  /// Agent `agent`'s items in `db` (which must serve its database), in
  /// `layout`; both must outlive the AgentIo. SetupError (a LayoutError
  /// among them) naming an item or quantity the layout or the team's table
  /// lacks.
  AgentIo(rtdb::Database& db, const rtdb::Layout& layout, int agent);
  ~AgentIo();
  AgentIo(const AgentIo&) = delete;
  AgentIo& operator=(const AgentIo&) = delete;

  /// The inputs as the agent's database holds them now; `dt_s` since the last decision.
  AgentInput read(double dt_s);
  void write(const AgentOutput& out);

 private:
  struct Items;
  std::unique_ptr<Items> items_;
};

}  // namespace canhil::laptop
