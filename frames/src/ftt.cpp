#include "canhil/frames/ftt.hpp"

#include <bit>
#include <numeric>
#include <sstream>

#include "canhil/frames/wire.hpp"

namespace canhil::frames {

FttSchedule::FttSchedule(const MessageSet& set, const FttConfig& config) : config_(config) {
  const Nanos ec = config.elementary_cycle;
  if (ec <= Nanos{0}) throw SetupError("the elementary cycle must be positive");
  if (config.bit_rate == 0) throw SetupError("the bit rate must be positive");
  auto us = [](Nanos t) { return std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(t).count()); };
  Nanos longest_async{0};
  Nanos tm_time{0};         // the TM's worst-case wire time
  std::uint32_t cycle = 1;  // ECs after which the schedule repeats
  for (const MessageCodec& m : set.codec().messages()) {
    const FttInfo& info = set.ftt(m);
    const Nanos wire = bits_to_time(worst_case_frame_bits(m.def().length, m.def().extended), config.bit_rate);
    if (info.kind == FttKind::kTrigger) {
      tm_time = wire;
      if (info.period != ec) {
        throw SetupError("the trigger message " + m.def().name + " has period " + us(info.period) +
                         " us but the elementary cycle is " + us(ec) +
                         " us; make them equal (GenMsgCycleTime in the DBC, or the EC setting)");
      }
    } else if (info.kind == FttKind::kAsync) {
      longest_async = std::max(longest_async, wire);
    } else {
      if (info.period.count() % ec.count() != 0) {
        throw SetupError("message " + m.def().name + " has period " + us(info.period) +
                         " us, not a whole number of elementary cycles (" + us(ec) +
                         " us); change its GenMsgCycleTime or the EC");
      }
      const auto i = static_cast<std::size_t>(info.index);
      period_ecs_[i] = static_cast<std::uint32_t>(info.period.count() / ec.count());
      frame_time_[i] = wire;
      cycle = std::lcm(cycle, period_ecs_[i]);
    }
  }
  std::uint64_t worst_ec = 0;
  Nanos longest{0};  // the longest synchronous window of the cycle
  if (cycle <= kMostTabled) {
    cycle_bitmaps_.resize(cycle);
    for (std::uint64_t k = 0; k < cycle; ++k) cycle_bitmaps_[k] = due(k);
  }
  for (std::uint64_t k = 0; k < cycle; ++k) {
    const Nanos w = sync_window(bitmap(k));
    if (w > longest) {
      longest = w;
      worst_ec = k;
    }
  }
  const Nanos needed = tm_time + longest_async + longest;
  if (needed > ec) {
    std::ostringstream os;
    os << "the FTT schedule does not fit the " << us(ec) << " us elementary cycle: the trigger message (" << us(tm_time)
       << " us), one asynchronous frame (" << us(longest_async) << " us) and the synchronous window of EC " << worst_ec
       << " (" << us(longest) << " us, messages";
    const std::uint32_t b = bitmap(worst_ec);
    for (int i = 0; i < 32; ++i) {
      if ((b >> i) & 1u) os << ' ' << set.sync_message(i)->name();
    }
    os << ") need " << us(needed) << " us; lengthen the EC, raise the bit rate or lengthen periods";
    throw SetupError(os.str());
  }
}

std::uint32_t FttSchedule::due(std::uint64_t ec_index) const noexcept {
  std::uint32_t b = 0;
  for (std::size_t i = 0; i < 32; ++i) {
    if (period_ecs_[i] != 0 && ec_index % period_ecs_[i] == 0) b |= 1u << i;
  }
  return b;
}

Nanos FttSchedule::sync_window(std::uint32_t b) const noexcept {
  Nanos w{0};
  for (; b != 0; b &= b - 1) w += frame_time_[static_cast<std::size_t>(std::countr_zero(b))];
  return w == Nanos{0} ? w : w + config_.sync_window_guard;
}

}  // namespace canhil::frames
