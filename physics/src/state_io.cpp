// WorldState to text and back. Every double is written in C99 hexadecimal
// floating point (%a), so that the round trip is exact; one record per line:
//   canhil-world-state 2
//   time <t>  seed <s>  ball <13 numbers>
//   robots <n>, then per robot: chassis <13>, wheel <13> x3, motors <...>, kick <...>
// (version 1, still read, had a wheel mode before each motor's target speed).
//   obstacles <m>, then obstacle <13> each
#include <cinttypes>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "canhil/physics/world.hpp"

namespace canhil::physics {
namespace {

void put(std::ostream& os, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, " %a", v);
  os << buf;
}

void put_body(std::ostream& os, const char* key, const BodyState& b) {
  os << key;
  for (double v : b.position) put(os, v);
  for (double v : b.quaternion) put(os, v);
  for (double v : b.linear_velocity) put(os, v);
  for (double v : b.angular_velocity) put(os, v);
  os << ' ' << (b.enabled ? 1 : 0) << '\n';
}

class LineReader {
 public:
  LineReader(std::istream& in, std::string file) : in_(in), file_(std::move(file)) {}
  /// Next line, which must start with `key`; the rest as a stream.
  std::istringstream expect(const std::string& key) {
    std::string line;
    if (!std::getline(in_, line)) fail("ends early; expected a \"" + key + "\" line");
    ++line_no_;
    std::istringstream is(line);
    std::string word;
    is >> word;
    if (word != key) fail("expected \"" + key + "\", found \"" + word + "\"");
    return is;
  }
  double number(std::istringstream& is) {
    std::string word;
    if (!(is >> word)) fail("has too few numbers");
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') fail("\"" + word + "\" is not a number");
    return v;
  }
  long long integer(std::istringstream& is) {
    long long v = 0;
    if (!(is >> v)) fail("expected a whole number");
    return v;
  }
  BodyState body(const std::string& key) {
    auto is = expect(key);
    BodyState b;
    for (double& v : b.position) v = number(is);
    for (double& v : b.quaternion) v = number(is);
    for (double& v : b.linear_velocity) v = number(is);
    for (double& v : b.angular_velocity) v = number(is);
    const long long enabled = integer(is);
    if (enabled != 0 && enabled != 1) fail("has an enabled flag that is not 0 or 1");
    b.enabled = enabled == 1;
    return b;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw SetupError(file_ + ":" + std::to_string(line_no_) + ": world state " + what +
                     "; give a file written by `canhil run --save-world FILE`");
  }

 private:
  std::istream& in_;
  std::string file_;
  int line_no_ = 0;
};

}  // namespace

void save_state(const WorldState& s, const std::filesystem::path& path) {
  std::ofstream os(path);
  if (!os) throw SetupError("cannot write the world state to " + path.string() + "; give a path in a writable folder");
  os << "canhil-world-state 2\n";
  os << "time";
  put(os, s.time_s);
  os << "\nseed " << s.seed << '\n';
  put_body(os, "ball", s.ball);
  os << "robots " << s.robots.size() << '\n';
  for (const RobotState& r : s.robots) {
    put_body(os, "chassis", r.chassis);
    for (const BodyState& w : r.wheels) put_body(os, "wheel", w);
    os << "motors";
    for (std::size_t n = 0; n < 3; ++n) {
      put(os, r.wheel_angle_rad[n]);
      put(os, r.hinge_angle_rad[n]);
      put(os, r.wheel_target_radps[n]);
      put(os, r.motor_current_a[n]);
    }
    os << "\nkick";
    put(os, r.kicker_voltage_v);
    os << ' ' << r.grabber_mode;
    put(os, r.grabber_release_left_s);
    put(os, r.last_kick_time_s);
    for (double c : r.charge) put(os, c);
    os << '\n';
  }
  os << "obstacles " << s.obstacles.size() << '\n';
  for (std::size_t i = 0; i < s.obstacles.size(); ++i) {
    put_body(os, "obstacle", s.obstacles[i]);
    os << "idle " << (i < s.obstacle_idle_steps.size() ? s.obstacle_idle_steps[i] : 0) << '\n';
  }
  if (!os) throw SetupError("cannot write the world state to " + path.string() + "; give a path in a writable folder");
}

WorldState load_state(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw SetupError("cannot read a world state from " + path.string() + "; does the file exist?");
  LineReader r(in, path.string());
  WorldState s;
  long long version = 0;
  {
    auto is = r.expect("canhil-world-state");
    version = r.integer(is);
    if (version != 1 && version != 2) r.fail("has an unknown version; this canhil reads versions 1 and 2");
  }
  {
    auto is = r.expect("time");
    s.time_s = r.number(is);
  }
  {
    auto is = r.expect("seed");
    s.seed = static_cast<unsigned long>(r.integer(is));
  }
  s.ball = r.body("ball");
  auto robots_line = r.expect("robots");
  const long long robots = r.integer(robots_line);
  if (robots < 0 || robots > 1000) r.fail("has an impossible robot count");
  for (long long i = 0; i < robots; ++i) {
    RobotState rs;
    rs.chassis = r.body("chassis");
    for (BodyState& w : rs.wheels) w = r.body("wheel");
    auto m = r.expect("motors");
    for (std::size_t n = 0; n < 3; ++n) {
      rs.wheel_angle_rad[n] = r.number(m);
      rs.hinge_angle_rad[n] = r.number(m);
      // Version 1 had a wheel mode before the target; only speed control (0) was ever written.
      if (version == 1 && r.integer(m) != 0) r.fail("has a wheel mode this canhil no longer has (speed control only)");
      rs.wheel_target_radps[n] = r.number(m);
      rs.motor_current_a[n] = r.number(m);
    }
    auto k = r.expect("kick");
    rs.kicker_voltage_v = r.number(k);
    rs.grabber_mode = static_cast<int>(r.integer(k));
    rs.grabber_release_left_s = r.number(k);
    rs.last_kick_time_s = r.number(k);
    for (double& c : rs.charge) c = r.number(k);
    s.robots.push_back(rs);
  }
  auto obstacles_line = r.expect("obstacles");
  const long long obstacles = r.integer(obstacles_line);
  if (obstacles < 0 || obstacles > 10000) r.fail("has an impossible obstacle count");
  for (long long i = 0; i < obstacles; ++i) {
    s.obstacles.push_back(r.body("obstacle"));
    auto idle = r.expect("idle");
    s.obstacle_idle_steps.push_back(static_cast<int>(r.integer(idle)));
  }
  return s;
}

}  // namespace canhil::physics
