// `canhil rtdb list|dump|watch|replicate`: look into the RTDB of every agent on
// this machine (canhil's shipped item configuration), and run the replicator.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/replicator.hpp"
#include "canhil/rtdb/rtdb.h"
#include "commands.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

int item_by_name(const std::string& name) {
  for (int i = 0; i < DB_item_count(); ++i) {
    if (name == DB_item_name(i)) return i;
  }
  std::string names;
  for (int i = 0; i < DB_item_count(); ++i) names += std::string(names.empty() ? "" : ", ") + DB_item_name(i);
  throw SetupError("no RTDB item named " + name + "; the items are " + names);
}

int agent_option(const std::optional<std::string>& v, const char* option, int fallback) {
  if (!v) return fallback;
  for (int a = 0; a < DB_agent_count(); ++a) {
    if (*v == DB_agent_name(a) || *v == std::to_string(a)) return a;
  }
  throw UsageError(std::string(option) + " " + *v + " is not an agent number or name");
}

std::string decode(const std::string& item, const std::vector<unsigned char>& raw) {
  char buf[512];
  auto as = [&](auto* p) {
    std::memcpy(p, raw.data(), std::min(raw.size(), sizeof(*p)));
    return p;
  };
  if (item == "CMD_VEL") {
    CMD_Vel v;
    as(&v);
    std::snprintf(buf, sizeof buf, "vx=%.3f m/s vy=%.3f m/s va=%.3f rad/s smallAdjustment=%d", v.vx, v.vy, v.va,
                  v.smallAdjustment);
  } else if (item == "CMD_POS") {
    CMD_Pos p;
    as(&p);
    std::snprintf(buf, sizeof buf, "px=%.4f py=%.4f pa=%.5f dx=%.4f dy=%.4f da=%.5f", p.px, p.py, p.pa, p.dx, p.dy,
                  p.da);
  } else if (item == "CMD_KICKER") {
    CMD_Kicker k;
    as(&k);
    std::snprintf(buf, sizeof buf, "power=0x%02X (%s, %d) engLvlHigh=%d engLvlLow=%d", k.power,
                  (k.power & 0x80) ? "low" : "high", k.power & 0x7F, k.engLvlHigh, k.engLvlLow);
  } else if (item == "CMD_GRABBER") {
    CMD_Grabber g;
    as(&g);
    std::snprintf(buf, sizeof buf, "mode=%d", g.mode);
  } else if (item == "CMD_INFO") {
    CMD_Info i;
    as(&i);
    std::snprintf(buf, sizeof buf, "logic=%.2f V power12=%.2f V power24=%.2f V kicker=%.2f V justKicked=%d",
                  i.Voltage_logic / 100.0, i.Voltage_power12 / 100.0, i.Voltage_power24 / 100.0,
                  i.Kicker_voltage / 100.0, i.justKicked);
  } else if (item == "CMD_IMU") {
    CMD_Imu i;
    as(&i);
    std::snprintf(buf, sizeof buf, "compass=%d deg yaw=%.2f deg rawYaw=%d", i.compass, i.yaw / 100.0, i.rawYaw);
  } else if (item == "CMD_GRABBER_INFO") {
    CMD_Grabber_Info g;
    as(&g);
    std::snprintf(buf, sizeof buf, "ballEngaged=%d grabberMode=%d", g.ballEngaged, g.grabberMode);
  } else if (item == "CMD_SETPOSE") {
    CMD_SetPose s;
    as(&s);
    std::snprintf(buf, sizeof buf, "px=%.3f py=%.3f pa=%.4f command=%d pending=%d", s.px, s.py, s.pa, s.command,
                  s.pending);
  } else if (item == "ROBOT_WS") {
    RobotWS w;
    as(&w);
    std::snprintf(buf, sizeof buf, "x=%.3f y=%.3f orientation=%.4f running=%d frame=%u", w.x, w.y, w.orientation,
                  w.running, w.frame);
  } else if (item == "COACH_INFO") {
    CoachInfo c;
    as(&c);
    std::snprintf(buf, sizeof buf, "gameState=%d formation=%d", c.gameState, c.formation);
  } else if (item == "CMD_HWERRORS") {
    CMD_HWerrors h;
    as(&h);
    std::string out;
    for (int r = 0; r < 5; ++r) {
      for (int c = 0; c < 8; ++c) {
        if (h.error_count[r][c] != 0)
          out += "[" + std::to_string(r) + "][" + std::to_string(c) + "]=" + std::to_string(h.error_count[r][c]) + " ";
      }
    }
    return out.empty() ? "all zero" : out;
  } else if (item == "VISION_INFO") {
    auto v = std::make_unique<VisionInfo>();
    as(v.get());
    std::string out = "balls=" + std::to_string(v->nBalls) + " lines=" + std::to_string(v->linePoints.nPoints) +
                      " obstacles=" + std::to_string(v->obstacles.nPoints);
    for (int b = 0; b < std::min(v->nBalls, MAX_BALLS); ++b) {
      std::snprintf(buf, sizeof buf, " ball%d=(%.3f, %.3f)", b, v->ball[b].x, v->ball[b].y);
      out += buf;
    }
    return out;
  } else {
    std::string hex;
    for (std::size_t i = 0; i < raw.size() && i < 64; ++i) {
      std::snprintf(buf, sizeof buf, "%02X", raw[i]);
      hex += buf;
    }
    return hex + (raw.size() > 64 ? "..." : "");
  }
  return buf;
}

std::string age_text(int age) { return age < 0 ? "-" : std::to_string(age) + " ms"; }

}  // namespace

int run_rtdb(Args& args) {
  const auto agent_text = args.option("--agent");
  const auto from_text = args.option("--from");
  rtdb::ReplicatorConfig cfg;
  try {
    if (const auto v = args.option("--period-ms")) cfg.period = std::chrono::milliseconds(std::stol(*v));
    if (const auto v = args.option("--delay-ms")) cfg.delay = std::chrono::milliseconds(std::stol(*v));
    if (const auto v = args.option("--loss")) cfg.loss = std::stod(*v);
    if (const auto v = args.option("--seed")) cfg.seed = std::stoull(*v);
  } catch (const std::exception&) {
    throw UsageError("--period-ms, --delay-ms, --loss and --seed take numbers");
  }
  const std::vector<std::string> words = args.positionals();
  const std::string sub = words.size() > 1 ? words[1] : "";
  if (sub != "list" && sub != "dump" && sub != "watch" && sub != "replicate") {
    throw UsageError("rtdb needs list, dump ITEM, watch ITEM or replicate");
  }
  if (DB_init_all(0) != 0) throw UsageError("cannot open the RTDB (see the message above)");
  struct Closer {
    ~Closer() { DB_free_all(0); }
  } closer;
  stop_on_signals();

  if (sub == "list") {
    std::printf("%-14s %-18s %-7s %7s %10s\n", "agent", "item", "kind", "bytes", "age");
    for (int a = 0; a < DB_agent_count(); ++a) {
      for (int i = 0; i < DB_item_count(); ++i) {
        const int kind = DB_item_shared(a, i);
        if (kind < 0) continue;
        std::vector<unsigned char> raw(static_cast<std::size_t>(DB_item_size(i)));
        std::printf("%-14s %-18s %-7s %7d %10s\n", DB_agent_name(a), DB_item_name(i), kind == 1 ? "shared" : "local",
                    DB_item_size(i), age_text(DB_get_from(a, a, i, raw.data())).c_str());
      }
    }
    return 0;
  }
  if (sub == "replicate") {
    const auto db = rtdb::open_builtin(rtdb::Scope::kAllAgents);
    rtdb::Replicator rep(*db, cfg);
    const can_nodes::WallClock clock;
    std::printf("canhil rtdb replicate: every %lld ms, delay %lld ms, loss %.2f; Ctrl-C stops\n",
                static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(cfg.period).count()),
                static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(cfg.delay).count()),
                cfg.loss);
    std::fflush(stdout);
    rep.run([&clock] { return clock.now(); }, [](Nanos t) { can_nodes::WallClock::sleep_until(t); }, g_stop);
    std::printf("canhil rtdb replicate: %llu cycles, %llu copies, %llu lost\n",
                static_cast<unsigned long long>(rep.stats().cycles),
                static_cast<unsigned long long>(rep.stats().copied), static_cast<unsigned long long>(rep.stats().lost));
    return 0;
  }
  if (words.size() < 3) throw UsageError("rtdb " + sub + " needs an item name, e.g. rtdb dump CMD_POS");
  const int item = item_by_name(words[2]);
  const char* env_agent = std::getenv("AGENT");
  const int agent = agent_option(
      env_agent != nullptr && !agent_text ? std::optional<std::string>(env_agent) : agent_text, "--agent", 1);
  const int from = agent_option(from_text, "--from", agent);
  std::vector<unsigned char> raw(static_cast<std::size_t>(DB_item_size(item)));
  do {
    const int age = DB_get_from(agent, from, item, raw.data());
    if (age < 0) {
      throw SetupError(std::string("agent ") + DB_agent_name(agent) + "'s database has no " + words[2] + " of " +
                       DB_agent_name(from));
    }
    std::printf("%s[%s] %s age %s: %s\n", DB_agent_name(agent), DB_agent_name(from), words[2].c_str(),
                age_text(age).c_str(), decode(words[2], raw).c_str());
    std::fflush(stdout);
    if (sub == "watch") std::this_thread::sleep_for(std::chrono::milliseconds(200));
  } while (sub == "watch" && !g_stop);
  return 0;
}

}  // namespace canhil::app
