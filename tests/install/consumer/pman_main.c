/* A team's program on canhil's PMan, from the install: CAMBADA's header
 * names and canhil's handle API, linked through pkg-config or the CMake
 * package (the static library, or libpman.so). */
#include <stdio.h>

#include "canhil/pman/pman_master.h"
#include "pman.h"

int main(void) {
  const canhil_pman_counters none = canhil_pman_get_counters(NULL); /* a call into the library */
  printf("pman table %zu key 0x%x\n", sizeof(PROC_TABLE_TYPE), CANHIL_PMAN_AGENT_KEY(1));
  return none.ticks == 0 && PMAN_close(PMAN_CLLEAVE) == -111 ? 0 : 1;
}
