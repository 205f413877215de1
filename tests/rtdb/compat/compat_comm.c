/* The team-communication side of compat_client: rtdb_comm.h, as CAMBADA's
 * comm daemon uses it (after DB_init as agent 1). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "rtdb.h"
#include "rtdb_comm.h"

int comm_checks(void) {
  int failures = 0;
  RTDBconf_var rec[MAX_RECS];
  const int n = DB_comm_ini(rec);
  CHECK(n == 1);
  CHECK(n >= 1 && rec[0].id == ROBOT_WS && rec[0].size == 20 && rec[0].period == 1);

  unsigned char ws[20];
  memset(ws, 7, sizeof ws);
  CHECK(DB_comm_put(Whoami(), ROBOT_WS, (int)sizeof ws, ws, 0) == -1); /* into the running agent */
  CHECK(DB_comm_put(SELF, ROBOT_WS, (int)sizeof ws, ws, 0) == -1);
  CHECK(DB_comm_put(CAMBADA_3, CMD_VEL, 16, ws, 0) == -1); /* a local item */
  CHECK(DB_comm_put(CAMBADA_3, ROBOT_WS, 0, ws, 250) == (int)sizeof ws);
  unsigned char seen[20];
  CHECK(DB_get(CAMBADA_3, ROBOT_WS, seen) >= 250);
  CHECK(memcmp(seen, ws, sizeof ws) == 0);
  return failures;
}
