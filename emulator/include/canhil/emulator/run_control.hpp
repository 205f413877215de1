// canhil/emulator/run_control.hpp — pause, step and speed of a virtual-time
// run: set from any thread (the viewer, the control socket), obeyed by the
// loop that drives the run. The loop asks next() what to do; it reads the
// wall clock itself and passes it in, so the plan is a pure function of the
// requests and the two clocks (and tests give it any wall time they like).
//
// Virtual time only ever stops on an elementary-cycle boundary: a pause takes
// effect at the next one and a step advances exactly one EC.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>

#include "canhil/base/time.hpp"

namespace canhil::emulator {

class RunControl {
 public:
  /// `speed`: virtual seconds per wall second, 0 for as fast as possible.
  explicit RunControl(Nanos ec, double speed = 0, bool paused = false);

  void pause();
  void resume();
  /// Advances `count` ECs (1..10000); SetupError unless paused.
  void step(std::uint32_t count = 1);
  /// 0 (as fast as possible) or kMinSpeed..kMaxSpeed; SetupError otherwise.
  void set_speed(double factor);
  static constexpr double kMinSpeed = 0.01;
  static constexpr double kMaxSpeed = 1000;
  /// The check set_speed makes: SetupError saying what a speed may be.
  static void check_speed(double factor);

  bool paused() const;
  double speed() const;
  Nanos ec() const noexcept { return ec_; }

  struct Plan {
    Nanos run_to{0};     ///< run the world up to here (an EC boundary; == now: nothing to run)
    Nanos wall_wait{0};  ///< then, if nothing was run, wait this long (or until a request)
  };
  /// What to do next at virtual time `now` and wall time `wall`, with the run ending at `end`.
  Plan next(Nanos now, Nanos wall, Nanos end);
  /// Waits until a request arrives or `wall_wait` passes (what the loop does with an idle plan).
  void wait(Nanos wall_wait);

  /// How much virtual time a max-speed chunk covers: small enough for a pause
  /// to take effect at once, big enough to cost nothing.
  static constexpr Nanos kChunk = std::chrono::milliseconds(50);
  /// Behind the paced schedule by more than this, the pace starts again from
  /// now instead of bursting to catch up.
  static constexpr Nanos kMaxBehind = std::chrono::milliseconds(250);

 private:
  Nanos boundary_at_or_after(Nanos t) const;
  Nanos boundary_at_or_before(Nanos t) const;

  const Nanos ec_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool paused_;
  double speed_;
  std::uint64_t steps_asked_ = 0;
  bool anchored_ = false;  // the pace's reference point is set
  Nanos anchor_virtual_{0}, anchor_wall_{0};
  std::uint64_t requests_ = 0;    // bumped by every request: wait() returns on it
  std::uint64_t planned_at_ = 0;  // requests_ when the last plan was made
};

}  // namespace canhil::emulator
