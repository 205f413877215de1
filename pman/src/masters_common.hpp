// pman/src/masters_common.hpp — what the two Masters implementations share:
// the counting (activations, epilogues, deadline misses) around their tick.
#pragma once

#include <algorithm>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "canhil/pman/masters.hpp"
#include "pman.h"

namespace canhil::pman {

/// A slot as canhil reports it (names are read up to their terminator or the field's end).
Process process_of(const PROC_TYPE& p);
/// A table key in hex.
std::string hex(int key);

class CountingMasters : public Masters {
 public:
  int tick(int agent) final;
  std::vector<ProcessCounts> counts(int agent) const final;

 protected:
  /// The implementation's own tick.
  virtual void do_tick(int agent) = 0;
  /// Names registered for `agent` (they get a count even if never activated).
  void registered(int agent, const std::vector<std::string>& names);

 private:
  struct Book {
    std::map<std::string, ProcessCounts> counts;
    std::map<std::string, bool> pending;  // activated at the last tick, not yet judged
  };
  std::map<int, Book> books_;
};

}  // namespace canhil::pman
