/* rtdbdefs.h — the constants and the record description of the CAMBADA RTDB
 * API, for programs written against CAMBADA's librtdb (canhil's own header:
 * CAMBADA's names and values, canhil's words; docs/rtdb.md).
 *
 * Not here: CAMBADA's System V keys (SHMEM_KEY, SHMEM_SECOND_TEAM_KEY).
 * canhil's segments use their own keys (RTDB_KEY, see canhil/rtdb/rtdb.h),
 * so a program that computed CAMBADA's keys itself must not compile against
 * this library. */
#ifndef CANHIL_RTDBDEFS_H
#define CANHIL_RTDBDEFS_H

#ifdef __cplusplus
extern "C" {
#endif

/* DB_get / DB_get_from: `from_agent` == SELF means the agent whose database
 * is read (DB_get: this process's agent). */
#define SELF 3333

/* The item table read at run time when no other is given, relative to the
 * working directory (CAMBADA runs its programs from bin/, next to config/). */
#define CONFIG_FILE "../config/rtdb.ini"

/* CAMBADA's limits: agents in one team (a program may size arrays with it;
 * canhil's library itself serves up to 64), and item records per agent. Item
 * ids in an rtdb.ini are 0 .. MAX_RECS - 1; DB_comm_ini fills at most
 * MAX_RECS records. */
#define MAX_AGENTS 7
#define MAX_RECS 100

/* One item as DB_comm_ini describes it: id, size in bytes, replication
 * period (in replication cycles). */
typedef struct {
  int id;
  int size;
  int period;
} RTDBconf_var;

#ifdef __cplusplus
}
#endif

#endif
