// canhil-agent [--pose X,Y,HEADING_DEG] [--goal-x M] [--power P] [--lob] [--duration S]
//
// The reference agent: woken after each vision frame (DB_wait_frame; the
// vision process writes VISION_INFO, then DB_signal_frame), it reads
// VISION_INFO, CMD_POS and CMD_GRABBER_INFO, decides (canhil/laptop/agent.hpp)
// and writes CMD_VEL, CMD_GRABBER and, once per kick, CMD_KICKER. With --pose
// it first asks the handler to set the odometry to that pose (CMD_SETPOSE).
// Without a vision frame for 200 ms it stops the robot.
#include <time.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "canhil/laptop/agent.hpp"
#include "canhil/laptop/agent_io.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "cli_numbers.hpp"
#include "rtdb_user.h"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }

double monotonic_s() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

int usage(const std::string& why) {
  std::fprintf(stderr,
               "canhil-agent: %s\nusage: canhil-agent [--pose X,Y,HEADING_DEG] [--goal-x M] [--power P] [--lob] "
               "[--duration S]\n",
               why.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  canhil::laptop::AgentConfig config;
  bool have_pose = false;
  double pose[3] = {0, 0, 0};
  double duration_s = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--lob") {
      config.low_kick = false;
      continue;
    }
    if (i + 1 >= argc) return usage("missing value for " + a);
    const std::string v = argv[++i];
    try {
      if (a == "--pose") {
        const auto c1 = v.find(',');
        const auto c2 = c1 == std::string::npos ? c1 : v.find(',', c1 + 1);
        if (c2 == std::string::npos) return usage("--pose takes X,Y,HEADING_DEG");
        pose[0] = canhil::laptop::parse_number(a, v.substr(0, c1));
        pose[1] = canhil::laptop::parse_number(a, v.substr(c1 + 1, c2 - c1 - 1));
        pose[2] = canhil::laptop::parse_number(a, v.substr(c2 + 1));
        have_pose = true;
      } else if (a == "--goal-x") {
        config.goal_x_m = canhil::laptop::parse_number(a, v);
      } else if (a == "--power") {
        config.kick_power = static_cast<int>(canhil::laptop::parse_number(a, v));
      } else if (a == "--duration") {
        duration_s = canhil::laptop::parse_number(a, v);
      } else {
        return usage("unknown option " + a);
      }
    } catch (const std::invalid_argument& e) {
      return usage(e.what());
    }
  }
  if (DB_init() != 0) return 2;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (have_pose) {
    CMD_SetPose p{static_cast<float>(pose[0]), static_cast<float>(pose[1]), static_cast<float>(pose[2] * M_PI / 180.0),
                  0, 1};
    DB_put(CMD_SETPOSE, &p);
  }
  std::printf("canhil-agent: agent %d (%s), opponent goal at x = %.2f m\n", Whoami(), DB_agent_name(Whoami()),
              config.goal_x_m);
  std::fflush(stdout);
  canhil::laptop::Agent agent(config);
  // Its items through canhil's RTDB (this process's agent, its team's set) in canhil's layout.
  const auto db = canhil::rtdb::open_builtin(canhil::rtdb::Scope::kOneAgent);
  const canhil::rtdb::Layout layout = canhil::rtdb::Layout::shipped("canhil");
  canhil::laptop::AgentIo io(*db, layout, Whoami());
  const double start = monotonic_s();
  double last = start;
  long frames = 0;
  canhil::laptop::AgentState shown = agent.state();
  while (!g_stop && (duration_s <= 0 || monotonic_s() - start < duration_s)) {
    const int woke = DB_wait_frame(200);
    if (woke < 0) break;
    if (woke == 1) {  // no vision: stand still
      CMD_Vel stop{0, 0, 0, false};
      DB_put(CMD_VEL, &stop);
      continue;
    }
    ++frames;
    const double now = monotonic_s();
    const canhil::laptop::AgentInput in = io.read(now - last);
    last = now;
    const canhil::laptop::AgentOutput out = agent.decide(in);
    io.write(out);
    if (out.kick != 0) {
      std::printf("canhil-agent: kick (0x%02X) at (%.2f, %.2f)\n", out.kick, in.x_m, in.y_m);
    }
    if (agent.state() != shown) {
      shown = agent.state();
      std::printf("canhil-agent: %s\n", canhil::laptop::state_name(shown));
      std::fflush(stdout);
    }
  }
  CMD_Vel stop{0, 0, 0, false};
  DB_put(CMD_VEL, &stop);
  std::printf("canhil-agent: %ld vision frames, %d kicks\n", frames, agent.kicks());
  DB_free();
  return 0;
}
