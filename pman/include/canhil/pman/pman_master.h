/* canhil/pman/pman_master.h — canhil's extension to PMan: a master as a
 * handle, so one process (canhil's emulated vision) can be the PMan master of
 * several robots at once, each with its own table, without CAMBADA's process
 * globals. The table, its keys and its protocol are exactly those of pman.h
 * (a CAMBADA client attaches to it unchanged); the two APIs share one
 * implementation.
 *
 * Typical use, robot N:
 *   int err = 0;
 *   canhil_pman* m = canhil_pman_open_master(N, &err);       // keys 0x9011 + 2N
 *   canhil_pman_procadd(m, "agent1", 1, 0, 10000);           // "agent<N>"
 *   canhil_pman_start(m);                                    // clients may attach now
 *   per frame: write VISION_INFO, then canhil_pman_tick(m);
 *   canhil_pman_close(m);                                    // SIGINT to the clients
 *
 * Threads: thread-compatible. Different handles may be used by different
 * threads at the same time; one handle must not be used by two threads at
 * once without the caller's own lock. Processes sharing a table take turns
 * through the table's semaphore. The handle API never touches the globals of
 * pman.h, and pman.h never touches a handle.
 *
 * Differences from a PMAN_init(PMAN_NEW) master: the scheduling policy of the
 * calling process is left alone (no SCHED_FIFO); there is no QoS function
 * (every slot's QoS data is one int, 0; the segment has the size of CAMBADA's
 * stock master, 246352 bytes); the table is published to clients only by
 * canhil_pman_start or the first tick, so no client can find the table before
 * its processes are registered; deadline misses are counted (see
 * canhil_pman_tick); waiting for the semaphore gives up after 1 s (a stuck or
 * hostile process holding it is counted, never waited for forever).
 *
 * Return codes are pman.h's: -1 a NULL handle or argument, or the semaphore
 * could not be taken; -2, -3, PMAN_E_ARG as PMAN_procadd; the open codes as
 * PMAN_init2(PMAN_NEW). */
#ifndef CANHIL_PMAN_PMAN_MASTER_H
#define CANHIL_PMAN_PMAN_MASTER_H

#include <sys/types.h>

#include "pman.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The table and semaphore key of robot `agent`'s omni-vision master. */
#define CANHIL_PMAN_AGENT_KEY(agent) (SHMEM_OCAM_PMAN_KEY + 2 * (agent))

/* A second team on the same computer (its processes started with
 * SECOND_RTDB=1, as for its RTDB set) meets its masters this far above the
 * first team's keys: 0x9111 + 2 x agent. canhil's PMAN_init adds it; a
 * library that does not know SECOND_RTDB (CAMBADA's) cannot. */
#define CANHIL_PMAN_SECOND_SET_OFFSET 0x100
/* The key of robot `agent` of team `set` (0 or 1). */
#define CANHIL_PMAN_SET_KEY(set, agent) (CANHIL_PMAN_AGENT_KEY(agent) + (set)*CANHIL_PMAN_SECOND_SET_OFFSET)

typedef struct canhil_pman canhil_pman;

/* What a master has seen. Every field only grows. */
typedef struct {
  unsigned long long ticks;           /* ticks done */
  unsigned long long activations;     /* SIGCONTs delivered */
  unsigned long long deadline_misses; /* activations of a process whose previous cycle had not ended */
  unsigned long long dead_clients;    /* clients found gone (ESRCH) and deattached */
  unsigned long long signal_failures; /* signals refused for another reason (EPERM: another user's pid) */
  unsigned long long bad_entries;     /* garbled table fields ignored or repaired (pid < 0, period <= 0, ...) */
  unsigned long long lock_failures;   /* the semaphore not obtained within 1 s, or gone */
} canhil_pman_counters;

/* Creates (or takes over and re-initialises) robot `agent`'s table, key
 * CANHIL_PMAN_AGENT_KEY(agent), unpublished: clients that find it wait in
 * PMAN_attach until canhil_pman_start. Returns the handle, or NULL with
 * *error (if error is not NULL) = PMAN_E_AGENT (agent < 0 or the key
 * overflows), PMAN_E_NOMEM, -11 shmget, -12 shmat, -13 semget, -14 semctl. */
canhil_pman* canhil_pman_open_master(int agent, int* error);

/* The same with explicit keys (tests, the front camera's 0x9010 keys).
 * PMAN_E_ARG for a key of 0. */
canhil_pman* canhil_pman_open_master_keys(key_t shm_key, key_t sem_key, int* error);

/* Registers process `name` (1..PNAME_LEN characters): period in ticks (> 0),
 * phase in ticks, deadline (stored only), no pid until its client attaches.
 * 0; -1; -2 table full; -3 already registered; PMAN_E_ARG. */
int canhil_pman_procadd(canhil_pman* h, const char* name, int period, int phase, int deadline);

/* Unregisters `name` (SIGINT to its client, if attached). 0; -1; -2 not registered. */
int canhil_pman_procdel(canhil_pman* h, const char* name);

/* Publishes the table: sets the semaphore to 1, so clients can attach.
 * Idempotent. 0; -1; -14 semctl failed. */
int canhil_pman_start(canhil_pman* h);

/* One tick (publishing the table first if needed): every attached process
 * due at this tick ((ticks - phase) % period == 0, the first tick being tick
 * 0) whose previous cycle has not ended — status still READY or ACTIV, no
 * epilogue since its last activation — counts a deadline miss (PROC_ndm + 1
 * in the table, and counters.deadline_misses; the deadline is implicitly the
 * next activation); then it is activated and sent SIGCONT as by PMAN_tick.
 * Returns the number of processes signalled at this tick (>= 0), or -1. */
int canhil_pman_tick(canhil_pman* h);

/* Copies `name`'s slot (status, pid, nact, ndm, last_start, last_finish, ...;
 * names NUL-terminated) into *out, taken under the semaphore. 0; -1; -2 not
 * registered. */
int canhil_pman_query(canhil_pman* h, const char* name, PROC_TYPE* out);

/* The counters so far (all zero for a NULL handle). */
canhil_pman_counters canhil_pman_get_counters(const canhil_pman* h);

/* Ends the master as PMAN_close(PMAN_CLFREE): SIGINT to every attached client,
 * the segment and the semaphore set removed; frees the handle (also on
 * error). 0; -1 NULL handle; -112, -113, -114 as PMAN_close. */
int canhil_pman_close(canhil_pman* h);

#ifdef __cplusplus
}
#endif

#endif
