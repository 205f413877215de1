#include "canhil/frames/ftt.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <numeric>
#include <sstream>

#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/wire.hpp"

namespace canhil::frames {

namespace {

std::string us(Nanos t) { return std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(t).count()); }

}  // namespace

std::vector<FttEntry> FttSchedule::entries(const MessageSet& set, std::uint32_t bit_rate) {
  if (bit_rate == 0) throw SetupError("the bit rate must be positive");
  std::vector<FttEntry> out;
  for (const MessageCodec& m : set.codec().messages()) {
    const FttInfo& info = set.ftt(m);
    out.push_back({m.def().name, info.kind, info.index, info.period,
                   bits_to_time(worst_case_frame_bits(m.def().length, m.def().extended), bit_rate)});
  }
  return out;
}

FttSchedule::FttSchedule(const MessageSet& set, const FttConfig& config)
    : FttSchedule(entries(set, config.bit_rate), config) {}

FttSchedule::FttSchedule(const std::vector<FttEntry>& entries, const FttConfig& config, Fit fit) : config_(config) {
  const Nanos ec = config.elementary_cycle;
  if (ec <= Nanos{0}) throw SetupError("the elementary cycle must be positive");
  if (config.bit_rate == 0) throw SetupError("the bit rate must be positive");
  std::array<const FttEntry*, 32> by_index{};
  for (const FttEntry& m : entries) {
    if (m.kind == FttKind::kTrigger) {
      tm_time_ = m.wire;
      if (m.period != ec) {
        throw SetupError("the trigger message " + m.name + " has period " + us(m.period) +
                         " us but the elementary cycle is " + us(ec) +
                         " us; make them equal (GenMsgCycleTime in the DBC, or the EC setting)");
      }
    } else if (m.kind == FttKind::kAsync) {
      longest_async_ = std::max(longest_async_, m.wire);
    } else {
      if (m.period <= Nanos{0} || m.period.count() % ec.count() != 0) {
        throw SetupError("message " + m.name + " has period " + us(m.period) +
                         " us, not a whole number of elementary cycles (" + us(ec) +
                         " us); change its GenMsgCycleTime or the EC");
      }
      if (m.index < 0 || m.index > 31) {
        throw SetupError("message " + m.name + " has FttIndex " + std::to_string(m.index) +
                         "; a synchronous message needs a bit 0..31 of sync_bitmap");
      }
      const auto i = static_cast<std::size_t>(m.index);
      if (by_index[i] != nullptr) {
        throw SetupError("message " + m.name + " has FttIndex " + std::to_string(m.index) + " like " +
                         by_index[i]->name + "; give each synchronous message its own index");
      }
      by_index[i] = &m;
      period_ecs_[i] = static_cast<std::uint32_t>(m.period.count() / ec.count());
      frame_time_[i] = m.wire;
      cycle_ = std::lcm(cycle_, std::uint64_t{period_ecs_[i]});
    }
  }
  if (cycle_ <= kMostTabled) {
    cycle_bitmaps_.resize(cycle_);
    for (std::uint64_t k = 0; k < cycle_; ++k) cycle_bitmaps_[k] = due(k);
  }
  for (std::uint64_t k = 0; k < cycle_; ++k) {
    const Nanos w = sync_window(bitmap(k));
    if (w > longest_window_) {
      longest_window_ = w;
      worst_ec_ = k;
    }
  }
  const Nanos needed = tm_time_ + longest_async_ + longest_window_;
  if (needed <= ec) return;
  std::ostringstream os;
  os << "the FTT schedule does not fit the " << us(ec) << " us elementary cycle: the trigger message (" << us(tm_time_)
     << " us), one asynchronous frame (" << us(longest_async_) << " us) and the synchronous window of EC " << worst_ec_
     << " (" << us(longest_window_) << " us, messages";
  const std::uint32_t b = bitmap(worst_ec_);
  for (std::size_t i = 0; i < 32; ++i) {
    if ((b >> i) & 1u) os << ' ' << by_index[i]->name;
  }
  os << ") need " << us(needed) << " us; lengthen the EC, raise the bit rate or lengthen periods";
  misfit_ = os.str();
  if (fit == Fit::kRequire) throw SetupError(misfit_);
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

Nanos ec_start(const CanFrame& tm, Nanos stamp, const FttConfig& config) noexcept {
  if (config.stamps == StampAt::kStartOfFrame || config.bit_rate == 0) return stamp;
  // Every slave on a bus asks about the same TM in turn: its wire time is
  // worked out once, and known again by two words (its header; its bytes).
  const std::uint64_t header = std::uint64_t{tm.id} | (std::uint64_t{tm.extended} << 32) |
                               (std::uint64_t{static_cast<std::uint8_t>(tm.kind)} << 40) |
                               (std::uint64_t{tm.len} << 48) | (std::uint64_t{tm.len8_dlc} << 56);
  static_assert(kMaxDataBytes == sizeof(std::uint64_t));
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, tm.data.data(), sizeof bytes);
  thread_local std::uint64_t last_header = 0, last_bytes = 0;
  thread_local std::uint32_t last_rate = 0;
  thread_local Nanos last_time{0};
  if (last_rate != config.bit_rate || header != last_header || bytes != last_bytes) {
    last_header = header;
    last_bytes = bytes;
    last_rate = config.bit_rate;
    last_time = bits_to_time(count_bits(wire_frame(tm)).total() - kIntermissionBits, config.bit_rate);
  }
  return stamp - last_time;  // the end of frame is before it
}

}  // namespace canhil::frames
