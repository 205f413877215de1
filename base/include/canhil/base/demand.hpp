// canhil/base/demand.hpp — always-on invariant checks.
//
// CANHIL_DEMAND(cond, message): a broken invariant (a bug, not bad input)
// prints file:line and the message and aborts, in every build type. Bad input
// and set-up mistakes use SetupError or counters instead (docs/errors.md).
#pragma once

#include <cstdio>
#include <cstdlib>

#define CANHIL_DEMAND(cond, message)                                                                         \
  do {                                                                                                       \
    if (!(cond)) {                                                                                           \
      std::fprintf(stderr, "%s:%d: canhil invariant broken: %s (%s)\n", __FILE__, __LINE__, message, #cond); \
      std::abort();                                                                                          \
    }                                                                                                        \
  } while (false)
