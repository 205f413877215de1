/* tests/rtdb/compat/check.h — a failed check is reported with its place and
 * counted in the caller's `failures`; the program goes on. */
#ifndef CANHIL_TESTS_COMPAT_CHECK_H
#define CANHIL_TESTS_COMPAT_CHECK_H

#include <stdio.h>

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                              \
    }                                                                          \
  } while (0)

#endif
