// `canhil bench --part match` (bench_match.hpp).
#include "bench_match.hpp"

#include <sched.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "canhil/base/time.hpp"
#include "canhil/emulator/match.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/step_timing.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::app {
namespace {

double cpu_now() { return to_seconds(thread_cpu_now()); }

// The world of a scenario stepped alone: virtual seconds per CPU second, and
// the contact points its steps made.
struct Alone {
  double factor = 0;
  double contacts_per_step = 0;
};

// How the robots of a world stepped alone move: not at all (the targets'
// yardstick), or every one driving all the time, as no match does, for the
// other end of what a match's physics can cost.
enum class Robots { kStanding, kDriving };

// Each wheel of a driving robot: a speed that swings between these (about
// +-1.7 m/s at the rim) over about 12 s, each wheel and robot out of phase,
// so the robots wander, turn, meet and push.
constexpr double kDriveRadps = 30;
constexpr double kDriveRadPerS = 0.5;

Alone physics_alone(const emulator::Scenario& s, double seconds, Robots robots = Robots::kStanding) {
  physics::World world(s.world);
  const auto steps = std::lround(seconds / s.world.simulation.step_s);
  const double cpu0 = cpu_now();
  for (long k = 0; k < steps; ++k) {
    if (robots == Robots::kDriving) {
      const double t = world.time_s();
      for (std::size_t r = 0; r < world.robot_count(); ++r) {
        for (int w = 0; w < 3; ++w) {
          world.robot(r).set_wheel_speed(w,
                                         kDriveRadps * std::sin(kDriveRadPerS * t + static_cast<double>(r) + 2.1 * w));
        }
      }
    }
    world.step();
  }
  const double factor = seconds / (cpu_now() - cpu0);
  return {factor, static_cast<double>(world.contact_points()) / static_cast<double>(std::max(1L, steps))};
}

// Where one run's CPU time went: its world's steps and its vision, timed one
// by one, and the rest.
struct Split {
  double total_s = 0;
  emulator::StepTiming timing;

  double physics_s() const { return to_seconds(timing.physics.cpu); }
  double vision_s() const { return to_seconds(timing.vision); }
  double rest_s() const { return total_s - physics_s() - vision_s(); }
};

// One robot set in virtual time, everything on, as `canhil run` without
// --trace; its world steps and vision timed when `split` is given.
double everything_on(const emulator::Scenario& s, double seconds,
                     const std::shared_ptr<const frames::MessageSet>& messages, Split* split = nullptr) {
  emulator::SessionOptions options;
  options.messages = messages;
  options.time_steps = split != nullptr;
  const double cpu0 = cpu_now();
  emulator::Session session(emulator::plan_run(s, options));
  emulator::VirtualOptions driving;
  driving.record_trace = false;
  emulator::VirtualDriver driver(session, driving);
  driver.run_for(from_seconds(seconds));
  const double cpu = cpu_now() - cpu0;
  if (split != nullptr) {
    *split = {cpu, session.step_timing()};
  }
  return seconds / cpu;
}

// A match half of two teams: the referee, the tally and the FTT check on.
double match_half(const emulator::Scenario& s, double seconds,
                  const std::shared_ptr<const frames::MessageSet>& messages, Split* split = nullptr) {
  emulator::SessionOptions options;
  options.messages = messages;
  options.time_steps = split != nullptr;
  emulator::MatchOptions m;
  m.halves = 1;
  m.half_s = seconds;
  const double cpu0 = cpu_now();
  const emulator::MatchResult result = emulator::play_match(s, options, m);
  const double cpu = cpu_now() - cpu0;
  if (split != nullptr) {
    *split = {cpu, result.timing};
  }
  return seconds / cpu;
}

// One line of "where the time went": the run's physics, its vision and the
// rest, and its physics a step next to the same world stepped alone, its
// robots standing and then driving.
void print_split(const char* label, const Split& split, const Alone& standing, const Alone& driving, double seconds) {
  const emulator::PhysicsTiming& physics = split.timing.physics;
  const double physics_s = split.physics_s();
  const double vision_s = split.vision_s();
  const double rest = split.rest_s();
  const auto steps = static_cast<double>(std::max<std::uint64_t>(1, physics.steps));
  const auto percent = [&split](double s) { return 100 * s / split.total_s; };
  const auto per_step = [&](const Alone& a) { return seconds / a.factor / steps * 1e6; };
  std::printf(
      "    %-30s %6.3f s %3.0f %%   %6.3f s %3.0f %%   %6.3f s %3.0f %%   %5.1f us (%5.1f, %5.1f)   %5.1f (%5.1f, "
      "%5.1f)\n",
      label, physics_s, percent(physics_s), vision_s, percent(vision_s), rest, percent(rest), physics_s / steps * 1e6,
      per_step(standing), per_step(driving), physics.contacts_per_step(), standing.contacts_per_step,
      driving.contacts_per_step);
}

// What a target leaves of the run for everything but its physics (the
// physics as it ran), next to what the vision and the rest took.
void print_budget(const char* label, const Split& split, const Alone& alone, double seconds, double target) {
  const double left = seconds / alone.factor / target - split.physics_s();
  std::printf("    %-30s %6.3f s; its vision took %.3f s and the rest %.3f s (target %.2f)\n", label, left,
              split.vision_s(), split.rest_s(), target);
}

// The most a run could reach of its physics alone if nothing cost anything
// but its own physics (whose robots meet, push and form scrums, which their
// world standing does not), and then its camera too, which a team's agent
// cannot do without.
void print_ceiling(const char* label, const Split& split, const Alone& alone, double seconds, double target) {
  const double alone_s = seconds / alone.factor;  // the same world's CPU time alone
  const double physics_s = split.physics_s();
  const double with_vision_s = physics_s + split.vision_s();
  std::printf(
      "    %-30s its physics %.2f times its world alone's: %.2f of physics alone; with its vision, %.2f "
      "(target %.2f)\n",
      label, physics_s / alone_s, alone_s / physics_s, alone_s / with_vision_s, target);
}

// The rest of the bench on the core it runs on now: one core, as the targets say.
int stay_on_this_core() {
  const int cpu = sched_getcpu();
  if (cpu < 0) return -1;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(static_cast<std::size_t>(cpu), &set);
  return sched_setaffinity(0, sizeof set, &set) == 0 ? cpu : -1;
}

}  // namespace

bool bench_match(const std::optional<std::string>& config, double seconds,
                 const std::shared_ptr<const frames::MessageSet>& messages) {
  const emulator::Scenario five = emulator::load_scenario(emulator::shipped_scenario("five_robots.toml"));
  const std::filesystem::path path =
      config ? std::filesystem::path(*config) : emulator::shipped_scenario("two_teams.toml");
  const emulator::Scenario ten = emulator::load_scenario(path);
  const int core = stay_on_this_core();
  constexpr int kRounds = 3;
  std::printf(
      "canhil bench: matches on one core (%s), %g s of virtual time each, CPU time of this thread, "
      "the best of %d interleaved rounds\n",
      core >= 0 ? ("core " + std::to_string(core)).c_str() : "any core", seconds, kRounds);
  // Noise only ever adds CPU time: each figure is its fastest round, and the
  // rounds interleave so that a slow spell of the machine hits every figure.
  Alone reference;
  Alone reference_ten;
  Alone five_driving;
  Alone ten_driving;
  double five_on = 0;
  double ten_on = 0;
  Split five_split;
  Split ten_split;
  // The runs with their world steps timed, the CPU time of the fastest (the
  // timing's clock reads stay out of the factors).
  const auto keep_fastest = [](Split& best, const Split& next) {
    if (best.timing.physics.steps == 0 || next.total_s < best.total_s) best = next;
  };
  const auto keep_faster = [](Alone& best, const Alone& next) {
    if (next.factor > best.factor) best = next;
  };
  for (int round = 0; round < kRounds; ++round) {
    keep_faster(reference, physics_alone(five, seconds));
    keep_faster(reference_ten, physics_alone(ten, seconds));
    keep_faster(five_driving, physics_alone(five, seconds, Robots::kDriving));
    keep_faster(ten_driving, physics_alone(ten, seconds, Robots::kDriving));
    five_on = std::max(five_on, everything_on(five, seconds, messages));
    ten_on = std::max(ten_on, match_half(ten, seconds, messages));
    Split timed;
    everything_on(five, seconds, messages, &timed);
    keep_fastest(five_split, timed);
    match_half(ten, seconds, messages, &timed);
    keep_fastest(ten_split, timed);
  }

  // Issue 15's targets are factors on one core of these machines, set where
  // the same five-robot run was 130x; bench/against_base.sh measures them
  // against that code in the same run. Issue 35's are each scenario's factor
  // over its own world's physics alone, from this run.
  constexpr double five_target = 180;
  constexpr double ten_target = 80;
  constexpr double five_share_target = 0.85;
  constexpr double ten_share_target = 0.75;
  const double five_share = five_on / reference.factor;
  const double ten_share = ten_on / reference_ten.factor;
  const auto verdict = [](bool met) { return met ? "met" : "MISSED"; };
  std::printf("  physics alone, five_robots.toml:           %6.0fx  (for scale: the world with nothing around it)\n",
              reference.factor);
  std::printf("  physics alone, %-26s %6.0fx\n", (path.filename().string() + ":").c_str(), reference_ten.factor);
  std::printf(
      "  five robots, everything on:                %6.1fx  = %.2f of its physics alone  target >= %.0fx: %s; "
      ">= %.2f of its physics alone: %s\n",
      five_on, five_share, five_target, verdict(five_on >= five_target), five_share_target,
      verdict(five_share >= five_share_target));
  std::printf(
      "  %2zu robots, a match half, everything on:    %6.1fx  = %.2f of its physics alone  target >= %.0fx: %s; "
      ">= %.2f of its physics alone: %s\n",
      ten.robot_count(), ten_on, ten_share, ten_target, verdict(ten_on >= ten_target), ten_share_target,
      verdict(ten_share >= ten_share_target));
  std::printf(
      "  (these factors move with the machine's speed: bench/against_base.sh judges them against the code the "
      "issue measured, in the same run)\n");
  std::printf(
      "  where the CPU time went, in the fastest of %d more runs of each with its world steps and vision timed:\n"
      "    %-30s %-14s   %-14s   %-14s   %-22s   %s\n",
      kRounds, "", "physics", "the vision", "the rest", "physics a step", "contact points a step");
  print_split("five robots, everything on:", five_split, reference, five_driving, seconds);
  const std::string ten_label = std::to_string(ten.robot_count()) + " robots, a match half:";
  print_split(ten_label.c_str(), ten_split, reference_ten, ten_driving, seconds);
  std::printf("    (in brackets: the same world alone, its robots standing, then every robot driving all the time)\n");
  const emulator::PhysicsTiming& p = ten_split.timing.physics;
  std::printf(
      "    the %zu-robot half's physics: a step with one contact point more took %.2f us more (a line fitted "
      "over its %llu steps)\n",
      ten.robot_count(), p.us_per_contact(), static_cast<unsigned long long>(p.steps));
  std::printf("  the most each could reach with nothing else costing anything:\n");
  print_ceiling("five robots, everything on:", five_split, reference, seconds, five_share_target);
  print_ceiling(ten_label.c_str(), ten_split, reference_ten, seconds, ten_share_target);
  std::printf("  what each target leaves for everything but the run's physics, as it ran:\n");
  print_budget("five robots, everything on:", five_split, reference, seconds, five_share_target);
  print_budget(ten_label.c_str(), ten_split, reference_ten, seconds, ten_share_target);
  return five_on >= five_target && ten_on >= ten_target && five_share >= five_share_target &&
         ten_share >= ten_share_target;
}

}  // namespace canhil::app
