// team_agent — a test program that behaves as the CAMBADA agent does towards
// canhil: written here from the published facts (docs/layouts.md,
// tests/rtdb/cambada_facts.hpp), linked against a team's own RTDB library
// (the stand-in, tests/support/team_rtdb/) and a PMan library with CAMBADA's
// API, with a CAMBADA-like team's rtdb_user.h and rtdb.ini.
//
//   AGENT=1 team_agent --ini RTDB_INI [--name agent1] [--attack [--the-north DEG]]
//
// It attaches to its robot's PMan table (retrying while no master has made it),
// sleeps in sigsuspend, and per SIGCONT runs one cycle: reads VISION_INFO,
// CMD_POS, CMD_IMU and the base station's COACH_INFO; when the coach lets it
// play, drives to the ball and kicks it (CMD_VEL, CMD_KICKER, CMD_GRABBER),
// otherwise stands still; then PMAN_epilogue. With --attack it reads its side
// as CAMBADA's agent does (world/Compass.cpp, localization/UseCompass.cpp in
// cambada-pub): its orientation on the field is CMD_IMU's yaw minus theNorth
// (--the-north, -80 as in the release's cambada.conf.xml), turned by 180
// degrees when its goalColor in COACH_INFO is Blue (0); orientation 0 faces
// the goal it attacks. It then goes round behind the ball, faces that goal
// and kicks towards it. SIGINT (the master's
// PMAN_close) ends it. It prints what it did, one line per event, and its
// counts (at each change of the coach's word and at the end) for the tests:
//   team_agent: cycles N, before vision M, playing P, stopped S, kicks K, vision age A..B ms, clock moved in C
// (C: cycles in which CLOCK_MONOTONIC read differently at the start and at the
// end; the end comes after a little spinning on the CPU, so that a clock that
// moves under a running cycle, which lockstep must never do, is caught.)
// Exit status: 0 after SIGINT, 3 if the RTDB cannot be opened, 4 if its
// process name is not in the table.
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "pman.h"
#include "rtdb/cambada_facts.hpp"
#include "rtdb_api.h"
#include "rtdb_sim.h"
#include "support/cambada_like/rtdb_user.h"

namespace {

constexpr int kStart = 3;  // CAMBADA's SIGstart
constexpr int kBlue = 0;   // CAMBADA's WSColor Blue

struct Options {
  bool attack = false;        // kick towards the goal its team attacks (else: whichever way it faces)
  float the_north_deg = -80;  // cambada.conf.xml's theNorth
};

struct Counts {
  long cycles = 0, before_vision = 0, playing = 0, stopped = 0, kicks = 0, clock_moved = 0;
  int youngest_vision_ms = INT_MAX, oldest_vision_ms = INT_MIN;  // VISION_INFO's age as DB_get answers it
};

void print_counts(const Counts& n) {
  std::printf(
      "team_agent: cycles %ld, before vision %ld, playing %ld, stopped %ld, kicks %ld, vision age %d..%d ms, clock "
      "moved in %ld\n",
      n.cycles, n.before_vision, n.playing, n.stopped, n.kicks, n.youngest_vision_ms, n.oldest_vision_ms,
      n.clock_moved);
  std::fflush(stdout);
}

float wrap_pi(float a) { return std::remainder(a, 2.0F * static_cast<float>(M_PI)); }

// One cycle's command towards the ball (robot frame, x right, y forward, m)
// when the side does not matter: turn to it, go to it, kick what it holds.
bool chase(float bx, float by, facts::CMD_Vel& vel) {
  const float distance = std::hypot(bx, by);
  const float bearing = std::atan2(-bx, by);  // counter-clockwise from forward
  vel.va = std::clamp(2.0F * bearing, -2.0F, 2.0F);
  const float speed = std::abs(bearing) < 0.5F ? std::min(1.5F, 1.2F * distance) : 0.0F;
  vel.vx = speed * bx / std::max(distance, 0.01F);
  vel.vy = speed * by / std::max(distance, 0.01F);
  return distance < 0.35F && std::abs(bearing) < 0.3F;
}

// The same towards the goal the team attacks, `orientation` the robot's on
// the field (rad, counter-clockwise, 0 facing that goal): to a point behind
// the ball on the line to the goal, then through the ball, facing the goal.
bool attack(float bx, float by, float orientation, facts::CMD_Vel& vel) {
  // The goal's direction in the robot frame: `orientation` clockwise from forward.
  const float gx = std::sin(orientation), gy = std::cos(orientation);
  const float px = gy, py = -gx;          // across that direction
  const float along = bx * gx + by * gy;  // how far the ball is ahead of the robot, towards the goal
  const float across = bx * px + by * py;
  const bool behind = along > 0.2F && std::abs(across) < 0.2F;
  float tx = bx, ty = by;          // behind the ball and on its line: through it
  if (!behind && along > 0.35F) {  // behind it, off the line: to 0.7 m behind the ball
    tx = bx - 0.7F * gx;
    ty = by - 0.7F * gy;
  } else if (!behind) {  // beside or in front of it: round it on the robot's side first
    const float side = across <= 0 ? 1.0F : -1.0F;
    tx = bx - 0.5F * gx + side * 0.8F * px;
    ty = by - 0.5F * gy + side * 0.8F * py;
  }
  const float distance = std::hypot(tx, ty);
  const float speed = std::min(1.5F, 1.5F * distance);
  vel.vx = speed * tx / std::max(distance, 0.01F);
  vel.vy = speed * ty / std::max(distance, 0.01F);
  vel.va = std::clamp(-2.0F * orientation, -2.0F, 2.0F);
  const float to_ball = std::hypot(bx, by);
  return behind && to_ball < 0.4F && std::abs(orientation) < 0.25F && std::abs(std::atan2(-bx, by)) < 0.3F;
}

long long monotonic_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1'000'000'000LL + t.tv_nsec;
}

void cycle(int agent, const Options& options, Counts& n, bool& was_playing, int& goal_color) {
  ++n.cycles;
  facts::VisionInfo vision{};
  facts::CMD_Pos pos{};
  facts::CMD_Imu imu{};
  facts::CoachInfo coach{};
  const int vision_age = DB_get(agent, VISION_INFO, &vision);
  DB_get(agent, CMD_POS, &pos);
  DB_get(agent, CMD_IMU, &imu);
  DB_get(BASE_STATION, COACH_INFO, &coach);  // the base station's shared copy
  // Never written: CAMBADA's library answers INT_MIN. Any other negative age
  // is a written item (a library that reads its clock before the stamp can
  // answer -1 when the next write lands in between): fresh, not missing.
  if (vision_age == INT_MIN) {
    ++n.before_vision;
    return;
  }
  n.youngest_vision_ms = std::min(n.youngest_vision_ms, vision_age);
  n.oldest_vision_ms = std::max(n.oldest_vision_ms, vision_age);
  const facts::PlayerInfo& me = coach.playerInfo[agent - 1];
  const bool play = me.running && coach.gameState == kStart;
  if (options.attack && me.goalColor != goal_color) {
    std::printf("team_agent: goalColor %s: %s\n", me.goalColor == kBlue ? "Blue" : "Yellow",
                me.goalColor == kBlue ? "the compass turned by 180 degrees" : "the compass as it reads");
    goal_color = me.goalColor;
  }
  if (play != was_playing) {
    std::printf("team_agent: coach says %s (game state %d)\n", play ? "play" : "stop", coach.gameState);
    print_counts(n);
    was_playing = play;
  }
  facts::CMD_Vel vel{};
  facts::CMD_Grabber grabber{};
  if (play && vision.nBalls > 0) {
    ++n.playing;
    // The ball in the robot's frame (x right, y forward), metres.
    const float bx = vision.ball[0].position.x, by = vision.ball[0].position.y;
    float orientation = (static_cast<float>(imu.yaw) - options.the_north_deg) * static_cast<float>(M_PI / 180);
    if (me.goalColor == kBlue) orientation += static_cast<float>(M_PI);
    const bool kick_now = options.attack ? attack(bx, by, wrap_pi(orientation), vel) : chase(bx, by, vel);
    grabber.mode = std::hypot(bx, by) < 0.6F ? 1 : 0;
    if (kick_now) {
      facts::CMD_Kicker kick{30, 70, 35};
      DB_put(CMD_KICKER, &kick);
      ++n.kicks;
    }
  } else {
    ++n.stopped;
  }
  DB_put(CMD_VEL, &vel);
  DB_put(CMD_GRABBER, &grabber);
}

}  // namespace

int main(int argc, char** argv) {
  std::string ini, name;
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--attack") {
      options.attack = true;
      continue;
    }
    if (i + 1 >= argc) break;
    if (a == "--ini") ini = argv[++i];
    if (a == "--name") name = argv[++i];
    if (a == "--the-north") options.the_north_deg = std::strtof(argv[++i], nullptr);
  }
  const char* agent_text = std::getenv("AGENT");
  const int agent = agent_text != nullptr ? std::atoi(agent_text) : 0;
  if (ini.empty() || agent < 1) {
    std::fprintf(stderr, "usage: AGENT=N team_agent --ini RTDB_INI [--name NAME] [--attack [--the-north DEG]]\n");
    return 2;
  }
  if (name.empty()) name = "agent" + std::to_string(agent);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGCONT);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigprocmask(SIG_BLOCK, &set, nullptr);
  DB_set_config_file(ini.c_str());
  if (DB_init() != 0) {
    std::fprintf(stderr, "team_agent: cannot open the RTDB\n");
    return 3;
  }
  // As the CAMBADA agent: wait for the master's table, then attach.
  for (int waited = 0; PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH) != 0; ++waited) {
    PMAN_close(PMAN_CLLEAVE);
    if (waited == 0) std::printf("team_agent: no PMan table yet, waiting\n");
    std::fflush(stdout);
    usleep(100'000);
  }
  // A team's PMan library makes the table visible before the master has
  // registered its processes (PMAN_init, then PMAN_procadd): an agent that
  // attaches in between is refused. This one tries again for a moment before
  // it takes the refusal as final (CAMBADA's agent would exit at once).
  int refused = PMAN_attach(name.c_str(), getpid());
  for (int tries = 1; refused != 0 && tries < 20; ++tries) {
    usleep(100'000);
    refused = PMAN_attach(name.c_str(), getpid());
  }
  if (refused != 0) {
    std::printf("team_agent: %s is not in the PMan table\n", name.c_str());
    PMAN_close(PMAN_CLLEAVE);
    DB_free();
    return 4;
  }
  std::printf("team_agent: attached as %s\n", name.c_str());
  std::fflush(stdout);
  Counts n;
  bool was_playing = false;
  int goal_color = -1;  // not read yet
  while (true) {
    int sig = 0;
    sigwait(&set, &sig);
    if (sig != SIGCONT) break;
    const long long start = monotonic_ns();
    cycle(agent, options, n, was_playing, goal_color);
    volatile int spun = 0;  // a little work on the CPU, which no clock call stands in for
    for (int i = 0; i < 100'000; ++i) spun = spun + 1;
    if (monotonic_ns() != start) ++n.clock_moved;
    PMAN_epilogue(name.c_str());
  }
  facts::CMD_Vel stop{};
  DB_put(CMD_VEL, &stop);
  print_counts(n);
  PMAN_close(PMAN_CLLEAVE);
  DB_free();
  return 0;
}
