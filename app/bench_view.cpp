#include "bench_view.hpp"

#include <atomic>
#include <cstdio>
#include <thread>

#include "canhil/control/run_commands.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "canhil/viewer/page_client.hpp"
#include "virtual_loop.hpp"

namespace canhil::app {
namespace {

// A page: connects and takes every message until told to stop; counts the states.
class Page {
 public:
  explicit Page(std::uint16_t port) {
    thread_ = std::thread([this, port] {
      try {
        viewer::PageClient ws(port, "/ws");
        connected_ = true;
        while (!stop_) {
          if (ws.receive(std::chrono::seconds(1)).find("\"type\":\"state\"") != std::string::npos) ++states_;
        }
      } catch (const std::exception&) {
        // the server went away or a read timed out at the end
      }
    });
    while (!connected_ && !stop_) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ~Page() {
    stop_ = true;
    thread_.join();
  }
  std::uint64_t states() const { return states_; }

 private:
  std::atomic<bool> stop_{false}, connected_{false};
  std::atomic<std::uint64_t> states_{0};
  std::thread thread_;
};

struct Round {
  double factor = 0;
  double wall_s = 0;
  std::uint64_t states = 0;
};

// One run as `canhil run --virtual-time --quiet` makes it, with or without a page watching.
Round one_round(const emulator::Scenario& sc, const std::shared_ptr<const frames::MessageSet>& messages, double seconds,
                bool watched) {
  emulator::SessionOptions options;
  options.messages = messages;
  emulator::Session session(emulator::plan_run(sc, options));
  emulator::VirtualOptions vo;
  vo.record_trace = false;
  emulator::VirtualDriver driver(session, vo);
  control::Commands commands(session);
  emulator::RunControl clock(options.ftt.elementary_cycle);
  control::add_run_commands(commands, clock);
  viewer::LiveFeed feed(session, commands, &clock, "canhil-saves");
  std::unique_ptr<viewer::Server> server;
  std::unique_ptr<Page> page;
  if (watched) {
    viewer::ServerOptions o;
    o.port = 0;
    o.web_root = viewer::default_web_root();
    server = std::make_unique<viewer::Server>(o, feed);
    page = std::make_unique<Page>(server->port());
  }
  const std::atomic<bool> never{false};
  const auto wall0 = std::chrono::steady_clock::now();
  drive_virtual(driver, session, clock, from_seconds(seconds), never);
  Round r;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  r.factor = seconds / r.wall_s;
  if (page) r.states = page->states();
  return r;
}

}  // namespace

bool bench_view(const std::optional<std::string>& config, double seconds,
                const std::shared_ptr<const frames::MessageSet>& messages) {
  const std::filesystem::path path =
      config ? std::filesystem::path(*config) : emulator::shipped_scenario("five_robots.toml");
  const emulator::Scenario sc = emulator::load_scenario(path);
  std::printf(
      "canhil bench: the viewer: %s, %zu robot(s), %g s of virtual time per round, rounds alternating "
      "without and with a page taking the 30 Hz stream\n",
      path.string().c_str(), sc.robot_count(), seconds);
  // Alternating rounds, the best of each: the machine's noise falls on both alike.
  Round bare, watched;
  for (int k = 0; k < 3; ++k) {
    const Round b = one_round(sc, messages, seconds, false);
    const Round w = one_round(sc, messages, seconds, true);
    if (b.factor > bare.factor) bare = b;
    if (w.factor > watched.factor) watched = w;
  }
  const double ratio = bare.factor > 0 ? watched.factor / bare.factor : 0;
  std::printf("  without the viewer: %.0fx real time (%.3f s of wall time)\n", bare.factor, bare.wall_s);
  std::printf("  with a page connected: %.0fx real time (%.3f s), %llu states streamed (%.0f per second)\n",
              watched.factor, watched.wall_s, static_cast<unsigned long long>(watched.states),
              watched.wall_s > 0 ? static_cast<double>(watched.states) / watched.wall_s : 0.0);
  const bool met = ratio >= 0.9;
  std::printf("  kept with the viewer: %.2f of the factor  target >= 0.90: %s\n", ratio, met ? "met" : "MISSED");
  return met;
}

}  // namespace canhil::app
