// canhil/viewer/live_feed.hpp — what the viewer shows of a running session
// and does to it: the hello from its scenario, the detailed snapshot as the
// state (with the run's pause and speed and its measured real-time factor),
// every request through the run's control::Commands — the same code paths as
// the control socket and the scenario file.
#pragma once

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>

#include "canhil/control/commands.hpp"
#include "canhil/emulator/run_control.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/viewer/server.hpp"

namespace canhil::viewer {

/// The fault rules the page offers in its list (any rule --fault takes can be typed in).
inline constexpr const char* kFaultExamples[] = {"drop:M4_1:0.1",      "drop:M6_1:0.5",    "delay:M1:4",
                                                 "corrupt:M4_2:0:0.1", "duplicate:M3_1",   "silence:Motor2:0",
                                                 "error:M1:0.01",      "battery:power24:1"};

class LiveFeed final : public Feed {
 public:
  /// `control`: the virtual-time run's clock (nullptr in real time: no pause,
  /// step or speed). `save_folder`: where `save` writes (listed in the hello).
  /// Everything must outlive the feed.
  LiveFeed(emulator::Session& session, control::Commands& commands, emulator::RunControl* control,
           std::filesystem::path save_folder);

  nlohmann::json hello() override;
  nlohmann::json state() override;
  nlohmann::json request(std::string_view text) override;

  /// The run has ended: the page shows the final world (and says so).
  void set_ended() noexcept { ended_ = true; }

 private:
  emulator::Session& session_;
  control::Commands& commands_;
  emulator::RunControl* control_;
  std::filesystem::path save_folder_;
  std::atomic<bool> ended_{false};
  std::mutex rate_mutex_;  // pages ask from the server's one thread, but tests may call from others
  double last_time_s_ = -1;
  std::chrono::steady_clock::time_point last_wall_;
  double rate_ = 0;
};

/// The field, ball and robot sizes every page needs, from the world's parameters (the hello's common part).
nlohmann::json world_hello(const physics::WorldParams& world);

}  // namespace canhil::viewer
