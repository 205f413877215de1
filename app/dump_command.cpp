#include <atomic>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/frames/codec.hpp"
#include "canhil/frames/describe.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

using namespace canhil::frames;

/// Prints frames as they come and keeps the counts for the summary.
class Printer {
 public:
  /// `head` >= 0: print only that many frames (all are counted).
  Printer(const Codec& codec, bool json, long long head = -1) : codec_(codec), json_(json), head_(head) {}

  void print(Nanos time, const std::string& iface, const CanFrame& frame) {
    const Described d = describe(codec_, frame);
    ++frames_;
    const bool shown = head_ < 0 || static_cast<long long>(frames_) <= head_;
    if (frame.kind == FrameKind::kError) {
      ++error_frames_;
    } else if (d.message == nullptr) {
      ++unknown_;
    } else if (frame.kind == FrameKind::kData) {
      ++per_message_[std::string(d.message->name())];
      if (d.result.status == DecodeStatus::kWrongLength) ++wrong_length_;
      if (d.result.status == DecodeStatus::kOk && d.result.out_of_range != 0u) ++out_of_range_;
    }
    if (!shown) return;
    if (json_) {
      std::string obj = describe_json(frame, d);
      char stamp[48];
      const auto us = std::chrono::duration_cast<std::chrono::microseconds>(time).count();
      std::snprintf(stamp, sizeof stamp, "%lld.%06lld", static_cast<long long>(us / 1'000'000),
                    static_cast<long long>(us % 1'000'000));
      obj.insert(1, "\"time\":" + std::string(stamp) + ",\"iface\":" + json_quote(iface) + ",");
      std::fwrite(obj.data(), 1, obj.size(), stdout);
      std::fputc('\n', stdout);
    } else {
      const std::string line = format_log_line(time, iface, frame);
      std::printf("%-44s %s\n", line.c_str(), describe_text(frame, d).c_str());
    }
  }

  void summary(const char* source) const {
    std::fflush(stdout);  // the frames first, also when both go to one file
    if (head_ >= 0 && static_cast<long long>(frames_) > head_) {
      std::fprintf(stderr, "canhil dump: ... %llu more frames not shown (--head %lld)\n",
                   static_cast<unsigned long long>(frames_) - static_cast<unsigned long long>(head_), head_);
    }
    std::fprintf(stderr, "canhil dump: %llu frames from %s", static_cast<unsigned long long>(frames_), source);
    for (const auto& [name, n] : per_message_)
      std::fprintf(stderr, "%s %s %llu", name == per_message_.begin()->first ? ";" : ",", name.c_str(),
                   static_cast<unsigned long long>(n));
    std::fprintf(stderr, "\ncanhil dump: %llu unknown ids, %llu wrong lengths, %llu out of range, %llu error frames\n",
                 static_cast<unsigned long long>(unknown_), static_cast<unsigned long long>(wrong_length_),
                 static_cast<unsigned long long>(out_of_range_), static_cast<unsigned long long>(error_frames_));
  }
  bool clean() const { return unknown_ == 0 && wrong_length_ == 0 && out_of_range_ == 0; }
  std::uint64_t frames() const { return frames_; }

 private:
  const Codec& codec_;
  bool json_;
  long long head_;
  std::uint64_t frames_ = 0;
  std::uint64_t unknown_ = 0;
  std::uint64_t wrong_length_ = 0;
  std::uint64_t out_of_range_ = 0;
  std::uint64_t error_frames_ = 0;
  std::map<std::string, std::uint64_t> per_message_;
};

int dump_log(const Codec& codec, const std::string& path, bool json, long long head) {
  std::ifstream file;
  std::istream* in = &std::cin;
  if (path != "-") {
    file.open(path);
    if (!file) throw SetupError("cannot read log file " + path);
    in = &file;
  }
  Printer printer(codec, json, head);
  std::string line;
  int line_no = 0;
  std::uint64_t bad_lines = 0;
  while (std::getline(*in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    LogEntry entry;
    std::string error;
    if (!parse_log_line(line, entry, &error)) {
      std::fprintf(stderr, "%s:%d: %s\n", path.c_str(), line_no, error.c_str());
      ++bad_lines;
      continue;
    }
    printer.print(entry.time, entry.iface, entry.frame);
  }
  printer.summary(path.c_str());
  if (bad_lines > 0)
    std::fprintf(stderr, "canhil dump: %llu lines could not be read\n", static_cast<unsigned long long>(bad_lines));
  return printer.clean() && bad_lines == 0 ? 0 : 1;
}

int dump_live(const Codec& codec, const std::string& iface, bool json, long long count, double seconds) {
  auto bus = can_nodes::SocketCanBus::open(iface);
  bus->set_error_mask(frames::kErrorClassMask);
  stop_on_signals();
  const can_nodes::WallClock clock;
  const Nanos deadline =
      seconds > 0 ? clock.now() + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(seconds)) : kNever;
  Printer printer(codec, json);
  can_nodes::BusState last = bus->state();
  if (last != can_nodes::BusState::kUp)
    std::fprintf(stderr, "canhil dump: %s is %s\n", iface.c_str(), can_nodes::state_name(last));
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  while (!g_stop && (count < 0 || static_cast<long long>(printer.frames()) < count) && clock.now() < deadline) {
    if (!bus->wait_readable(std::chrono::milliseconds(100))) {
      bus->refresh_state();
    }
    while (!g_stop) {  // a flood's backlog stops at Ctrl-C (or the reader gone) too
      auto f = bus->receive();
      if (!f) break;
      printer.print(f->time, iface, f->frame);
      if (count >= 0 && static_cast<long long>(printer.frames()) >= count) break;
    }
    if (bus->state() != last) {
      last = bus->state();
      std::fprintf(stderr, "canhil dump: %s is %s\n", iface.c_str(), can_nodes::state_name(last));
      if (last == can_nodes::BusState::kGone) break;
    }
  }
  printer.summary(iface.c_str());
  const auto stats = bus->stats();
  if (stats.rx_overflow > 0) {
    std::fprintf(stderr, "canhil dump: %llu frames lost to receive-queue overflow\n",
                 static_cast<unsigned long long>(stats.rx_overflow));
  }
  return last == can_nodes::BusState::kGone ? 2 : (printer.clean() ? 0 : 1);
}

}  // namespace

int run_dump(Args& args, const std::optional<std::string>& dbc) {
  const bool json = args.flag("--json");
  const auto log = args.option("--log");
  const auto count_text = args.option("--count");
  const auto seconds_text = args.option("--seconds");
  const auto head = optional_number(args, "--head");
  const std::vector<std::string> words = args.positionals();
  if (head && !(*head >= 0 && *head == static_cast<double>(static_cast<long long>(*head)))) {
    throw UsageError("--head takes a number of frames, 0 or more");
  }
  const Codec codec(load_chosen_dbc(dbc));
  if (log) {
    if (words.size() != 1) throw UsageError("dump --log FILE takes no interface");
    return dump_log(codec, *log, json, head ? static_cast<long long>(*head) : -1);
  }
  if (head) throw UsageError("--head is for --log; a live dump takes --count N");
  if (words.size() != 2) throw UsageError("dump needs one interface (e.g. canhil dump vcan0) or --log FILE");
  long long count = -1;
  double seconds = 0;
  try {
    if (count_text) count = std::stoll(*count_text);
    if (seconds_text) seconds = std::stod(*seconds_text);
  } catch (const std::exception&) {
    throw UsageError("--count and --seconds take numbers");
  }
  return dump_live(codec, words[1], json, count, seconds);
}

}  // namespace canhil::app
