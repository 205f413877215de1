/* A CAMBADA-style C program on canhil's RTDB: it includes only CAMBADA's
 * header names (rtdb.h, rtdb_sim.h; rtdb_comm.h in compat_comm.c) and defines
 * its item types itself, as CAMBADA code does, including a `Vec` of its own.
 * Run as a test: exit status 0 when every check holds; own System V keys
 * (RTDB_KEY from the pid), nothing left behind. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): setenv
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/shm.h>
#include <unistd.h>

#include "check.h"
#include "rtdb.h"
#include "rtdb_sim.h"

typedef struct {
  float x, y;
} Vec; /* the program's own; canhil's headers must not clash with it */

typedef struct {
  float vx, vy, va;
  bool smallAdjustment;
} CMD_Vel;

typedef struct {
  Vec pos;
  float orientation;
  int running;
  unsigned int frame;
} RobotWS; /* canhil's ROBOT_WS is 20 bytes, like this */

int comm_checks(void); /* compat_comm.c */

static int failures = 0;

int main(void) {
  char key[32];
  const int base = 0x5C000000 + ((getpid() & 0xFFFF) << 6);
  snprintf(key, sizeof key, "%d", base);
  setenv("RTDB_KEY", key, 1);
  setenv("AGENT", "1", 1);

  CHECK(Whoami() == -1);
  CHECK(DB_init() == 0);
  CHECK(Whoami() == CAMBADA_1);
  CMD_Vel v = {0.5f, -0.25f, 1.0f, true};
  CHECK(DB_put(CMD_VEL, &v) == (int)sizeof v);
  CMD_Vel back;
  memset(&back, 0, sizeof back);
  const int age = DB_get(SELF, CMD_VEL, &back);
  CHECK(age >= 0 && age < 1000);
  CHECK(memcmp(&v, &back, sizeof v) == 0);
  CHECK(DB_get(CAMBADA_1, CMD_VEL, &back) >= 0);
  CHECK(DB_put_in(CAMBADA_1, CAMBADA_1, CMD_VEL, &v, 400) == (int)sizeof v);
  CHECK(DB_get(SELF, CMD_VEL, &back) >= 400);
  CHECK(DB_get(CAMBADA_2, CMD_VEL, &back) == -1); /* another robot's local item */

  CHECK(DB_init_all(0) == 0);
  RobotWS w = {{1.0f, 2.0f}, 0.5f, 1, 9};
  CHECK(DB_put_in(CAMBADA_2, CAMBADA_2, ROBOT_WS, &w, 0) == (int)sizeof w);
  RobotWS seen;
  CHECK(DB_get_from(CAMBADA_2, SELF, ROBOT_WS, &seen) >= 0 && seen.frame == 9);
  DB_free_all(0);

  failures += comm_checks();
  DB_free();
  for (int a = 0; a < N_AGENTS; ++a) CHECK(shmget(base + a, 0, 0) < 0); /* nothing left behind */
  printf("compat_client: %s\n", failures == 0 ? "all checks hold" : "FAILED");
  return failures == 0 ? 0 : 1;
}
