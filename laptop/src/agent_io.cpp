#include "canhil/laptop/agent_io.hpp"

#include <cstddef>

#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"

namespace canhil::laptop {
namespace {

// VisionInfo's last two fields, as they lie in it.
struct VisionBalls {
  canhil_vec2 ball[MAX_BALLS];
  int count;
};
static_assert(offsetof(VisionInfo, nBalls) - offsetof(VisionInfo, ball) == offsetof(VisionBalls, count) &&
                  sizeof(VisionInfo) - offsetof(VisionInfo, ball) == sizeof(VisionBalls),
              "VisionInfo ends with ball[] and nBalls");

}  // namespace

AgentInput AgentIo::read(double dt_s) {
  AgentInput in;
  in.dt_s = dt_s;
  // Of VISION_INFO (4.8 kB) it needs the balls only, at the item's end.
  VisionBalls balls{};
  DB_get_part(space_, SELF, VISION_INFO, offsetof(VisionInfo, ball), sizeof balls, &balls);
  in.ball_seen = balls.count > 0;
  if (in.ball_seen) {
    in.ball_x_m = balls.ball[0].x;
    in.ball_y_m = balls.ball[0].y;
  }
  CMD_Pos pos;
  DB_get_from(space_, SELF, CMD_POS, &pos);
  in.x_m = pos.px;
  in.y_m = pos.py;
  in.heading_rad = pos.pa;
  CMD_Grabber_Info gi;
  DB_get_from(space_, SELF, CMD_GRABBER_INFO, &gi);
  in.ball_engaged = gi.ballEngaged != 0;
  // The base station's orders, as the coach writes them into this robot's
  // database (canhil's layout: stop 1, halt 2, start 3, ...; 0 none yet).
  CoachInfo coach{};
  DB_get_from(space_, BASE_STATION, COACH_INFO, &coach);
  constexpr int kNoCoachYet = 0;
  constexpr int kStart = 3;
  in.play = coach.gameState == kNoCoachYet || coach.gameState == kStart;
  return in;
}

void AgentIo::write(const AgentOutput& out) {
  CMD_Vel vel{static_cast<float>(out.vx_mps), static_cast<float>(out.vy_mps), static_cast<float>(out.va_radps), false};
  DB_put_in(space_, SELF, CMD_VEL, &vel, 0);
  CMD_Grabber grab{static_cast<unsigned char>(out.grabber)};
  DB_put_in(space_, SELF, CMD_GRABBER, &grab, 0);
  if (out.kick != 0) {
    CMD_Kicker kick{out.kick, 0, 0};
    DB_put_in(space_, SELF, CMD_KICKER, &kick, 0);
  }
}

}  // namespace canhil::laptop
