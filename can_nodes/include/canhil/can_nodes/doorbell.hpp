// canhil/can_nodes/doorbell.hpp — who has frames waiting, without asking
// everyone: a receive queue rings its reader's index when a frame is queued,
// and a runner's delivery round visits only the indices rung (in order).
//
// Not thread-safe: the queues and the runner share one thread (virtual time).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace canhil::can_nodes {

class Doorbell {
 public:
  static constexpr std::size_t kNone = ~std::size_t{0};

  /// Room for indices 0..count-1 (grows; rings kept).
  void resize(std::size_t count) { words_.resize((count + 63) / 64, 0); }
  void ring(std::size_t index) noexcept { words_[index / 64] |= std::uint64_t{1} << (index % 64); }
  void clear(std::size_t index) noexcept { words_[index / 64] &= ~(std::uint64_t{1} << (index % 64)); }
  bool rung(std::size_t index) const noexcept { return ((words_[index / 64] >> (index % 64)) & 1u) != 0; }
  /// The smallest index rung at or after `from`, or kNone. Rings that come
  /// after a call are seen by the next one, so a round may go on while it
  /// rings further indices.
  std::size_t next(std::size_t from) const noexcept {
    std::size_t w = from / 64;
    if (w >= words_.size()) return kNone;
    std::uint64_t bits = words_[w] & (~std::uint64_t{0} << (from % 64));
    while (bits == 0) {
      if (++w == words_.size()) return kNone;
      bits = words_[w];
    }
    return w * 64 + static_cast<std::size_t>(std::countr_zero(bits));
  }

 private:
  std::vector<std::uint64_t> words_;
};

}  // namespace canhil::can_nodes
