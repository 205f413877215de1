// canhil/base/ring.hpp — a first-in first-out queue in one growing array: no
// allocation once it has been as long as it gets (a std::deque allocates and
// frees a block every few hundred bytes that pass through it).
//
// Not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace canhil::base {

template <class T>
class Ring {
 public:
  bool empty() const noexcept { return size_ == 0; }
  std::size_t size() const noexcept { return size_; }
  const T& front() const noexcept { return slots_[head_]; }
  T& front() noexcept { return slots_[head_]; }
  /// The i-th from the front (i < size()).
  const T& operator[](std::size_t i) const noexcept { return slots_[(head_ + i) & mask()]; }
  void push_back(const T& value) {
    if (size_ == slots_.size()) grow();
    slots_[(head_ + size_) & mask()] = value;
    ++size_;
  }
  void push_back(T&& value) {
    if (size_ == slots_.size()) grow();
    slots_[(head_ + size_) & mask()] = std::move(value);
    ++size_;
  }
  /// The slot after the back, now in the queue, as it was left (fill every
  /// field: no copy of a value made first).
  T& push_slot() {
    if (size_ == slots_.size()) grow();
    return slots_[(head_ + size_++) & mask()];
  }
  /// Drops the front; its slot keeps what it held (move it out first to reuse it).
  /// Emptied, it starts again at the first slot: a queue that is drained as
  /// it fills (a bus endpoint in virtual time) keeps writing the same few
  /// slots, which stay in the cache, instead of walking all of them.
  void pop_front() noexcept { head_ = --size_ == 0 ? 0 : static_cast<std::uint32_t>((head_ + 1) & mask()); }
  /// Drops everything (the slots stay, as pop_front leaves them).
  void clear() noexcept {
    head_ = 0;
    size_ = 0;
  }

 private:
  std::size_t mask() const noexcept { return slots_.size() - 1; }
  void grow() {
    std::vector<T> bigger(slots_.empty() ? 16 : slots_.size() * 2);
    for (std::size_t i = 0; i < size_; ++i) bigger[i] = std::move(slots_[(head_ + i) & mask()]);
    slots_ = std::move(bigger);
    head_ = 0;
  }

  // 32-bit places: a ring (a queue's head, say) fits in half a cache line
  // beside what its owner reads with it. No queue holds 2^32 items.
  std::vector<T> slots_;  // a power of two long
  std::uint32_t head_ = 0;
  std::uint32_t size_ = 0;
};

}  // namespace canhil::base
