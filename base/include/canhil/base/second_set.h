/* canhil/base/second_set.h — whether this process plays for the second team
 * of a run: SECOND_RTDB set and not "0" (CAMBADA's variable). One rule for
 * canhil's RTDB (its second set of databases), its PMan (the second team's
 * tables) and rtdb::Database; C and C++. */
#ifndef CANHIL_BASE_SECOND_SET_H
#define CANHIL_BASE_SECOND_SET_H

#include <stdlib.h>
#include <string.h>

static inline int canhil_second_set_from_environment(void) {
  const char* s = getenv("SECOND_RTDB");
  if (!s) return 0; /* no NULL: C++ includes this too */
  return *s != '\0' && strcmp(s, "0") != 0;
}

#endif /* CANHIL_BASE_SECOND_SET_H */
