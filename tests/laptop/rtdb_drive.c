/* rtdb_drive — a test program linked only against the RTDB library: plays the
 * agent by writing RTDB items, as a team's own code would.
 *   rtdb_drive vel VX VY VA SECONDS   CMD_VEL for SECONDS, then zero; prints CMD_POS
 *   rtdb_drive kick POWER             one kicker command; waits; prints CMD_KICKER.power
 *   rtdb_drive pos                    prints CMD_POS */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier)
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"

static void sleep_ms(long ms) {
  struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
  nanosleep(&t, NULL);
}

static int print_pos(void) {
  CMD_Pos p;
  const int age = DB_get(Whoami(), CMD_POS, &p);
  printf("CMD_POS %.4f %.4f %.5f age %d\n", p.px, p.py, p.pa, age);
  return age >= 0 ? 0 : 1;
}

int main(int argc, char** argv) {
  if (argc < 2 || DB_init() != 0) return 2;
  int status = 0;
  if (strcmp(argv[1], "vel") == 0 && argc == 6) {
    CMD_Vel v = {(float)atof(argv[2]), (float)atof(argv[3]), (float)atof(argv[4]), false};
    const long steps = (long)(atof(argv[5]) * 20);
    for (long i = 0; i < steps; ++i) {
      DB_put(CMD_VEL, &v);
      sleep_ms(50);
    }
    CMD_Vel stop = {0, 0, 0, false};
    DB_put(CMD_VEL, &stop);
    sleep_ms(800);
    status = print_pos();
  } else if (strcmp(argv[1], "kick") == 0 && argc == 3) {
    CMD_Kicker k = {(unsigned char)atoi(argv[2]), 0, 0};
    DB_put(CMD_KICKER, &k);
    sleep_ms(1500);
    DB_get(Whoami(), CMD_KICKER, &k);
    printf("CMD_KICKER power %d\n", k.power);
  } else if (strcmp(argv[1], "pos") == 0) {
    status = print_pos();
  } else {
    status = 2;
  }
  DB_free();
  return status;
}
