#include "islands.hpp"

#include <algorithm>
#include <numeric>
#include <utility>

namespace canhil::physics {

void Islands::reset(std::size_t bodies) {
  parent_.resize(bodies);
  std::iota(parent_.begin(), parent_.end(), 0);
  rows_.assign(bodies, 0);
  largest_ = 0;
}

int Islands::find(int body) {
  int root = body;
  while (parent_[static_cast<std::size_t>(root)] != root) root = parent_[static_cast<std::size_t>(root)];
  while (parent_[static_cast<std::size_t>(body)] != root) {
    body = std::exchange(parent_[static_cast<std::size_t>(body)], root);
  }
  return root;
}

void Islands::link(int a, int b, int rows) {
  if (a < 0) std::swap(a, b);
  if (a < 0) return;
  int ra = find(a);
  if (b >= 0) {
    int rb = find(b);
    if (rb != ra) {
      // The smaller root index stays the root: the same forest whatever the order of links.
      if (rb < ra) std::swap(ra, rb);
      parent_[static_cast<std::size_t>(rb)] = ra;
      rows_[static_cast<std::size_t>(ra)] += rows_[static_cast<std::size_t>(rb)];
    }
  }
  rows_[static_cast<std::size_t>(ra)] += rows;
  largest_ = std::max(largest_, rows_[static_cast<std::size_t>(ra)]);
}

int Islands::rows_of(int body) { return rows_[static_cast<std::size_t>(find(body))]; }

}  // namespace canhil::physics
