// canhil/base/spelling.hpp — the known word nearest to a mistyped one, for
// the "unknown key ...; did you mean ...?" of every configuration canhil
// reads (the world and scenario files, the layouts).
#pragma once

#include <algorithm>
#include <cstddef>
#include <string_view>
#include <vector>

namespace canhil {

/// Levenshtein distance: the fewest insertions, deletions and substitutions
/// of one character that turn `a` into `b`.
inline std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> prev(b.size() + 1);
  std::vector<std::size_t> cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

/// The candidate nearest to `word`, at most `max_distance` edits from it (the
/// first of equally near ones, in the candidates' order), or an empty view.
/// `candidates`: anything iterable whose elements convert to string_view.
template <class Candidates>
std::string_view nearest_word(std::string_view word, const Candidates& candidates, std::size_t max_distance = 3) {
  std::string_view best;
  std::size_t best_distance = max_distance + 1;
  for (const auto& candidate : candidates) {
    const std::string_view c(candidate);
    const std::size_t d = edit_distance(word, c);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

}  // namespace canhil
