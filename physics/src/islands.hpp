// physics/src/islands.hpp — the islands ODE is about to form, counted before
// it does: bodies joined by a joint (a wheel's hinge, this step's contacts)
// are one island, and each joint adds its constraint rows to its island.
//
// The world steps small islands with the exact solver and large ones (a
// scrum: the exact solver's cost grows with the cube of the rows) with
// QuickStep; this tells which is which. Bodies are numbered 0..n-1 by the
// caller; the static world (-1) joins nothing.
#pragma once

#include <cstddef>
#include <vector>

namespace canhil::physics {

class Islands {
 public:
  /// Every body alone, no rows.
  void reset(std::size_t bodies);
  /// A joint of `rows` rows between bodies a and b (either may be -1: the static world).
  void link(int a, int b, int rows);
  /// The rows of the island body `body` is in.
  int rows_of(int body);
  /// The largest island's rows.
  int largest() const noexcept { return largest_; }

 private:
  int find(int body);
  std::vector<int> parent_;
  std::vector<int> rows_;  // at each root
  int largest_ = 0;
};

}  // namespace canhil::physics
