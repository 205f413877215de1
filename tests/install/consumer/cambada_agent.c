/* A CAMBADA-style program built against an installed canhil: CAMBADA's header
 * names only (rtdb.h finds the team's own rtdb_user.h, team/), linked with
 * canhil's librtdb.so, which reads the team's rtdb.ini at DB_init
 * ($CANHIL_RTDB_INI here). Prints what it wrote and read back. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "rtdb.h"
#include "rtdb_sim.h"

typedef struct {
  float x, y;
} Vec; /* the team's own */

typedef struct {
  float vx, vy, va;
  bool smallAdjustment;
} CMD_Vel;

int main(void) {
  if (DB_init() != 0) return 1;
  CMD_Vel v = {1.0f, 2.0f, 0.5f, false};
  const int size = DB_put(CMD_VEL, &v);
  CMD_Vel back;
  memset(&back, 0, sizeof back);
  const int age = DB_get(SELF, CMD_VEL, &back);
  printf("cambada_agent: agent %d of %d, CMD_VEL %d bytes, read back vy %.1f, age %s\n", Whoami(), N_AGENTS, size,
         back.vy, age >= 0 && age < 1000 ? "fresh" : "wrong");
  DB_free();
  return size == (int)sizeof v && back.vy == 2.0f ? 0 : 1;
}
