/* pman.h — canhil's process manager (PMan), table-compatible with CAMBADA's
 * libpman: the same function names and signatures, constants, shared-memory
 * table layout and semaphore protocol, so a CAMBADA agent linked with either
 * library works with a master built on either library. (canhil's own header
 * and implementation; docs/pman.md tells the whole story.)
 *
 * The model. A master (on a robot: the omni-vision process) creates a process
 * table in System V shared memory and a one-semaphore set under the same key
 * (SHMEM_OCAM_PMAN_KEY + 2*AGENT, pmandefs.h), registers its clients by name
 * (PMAN_procadd) and calls PMAN_tick() once per frame. A tick activates every
 * attached client that is due — (ticks - phase) % period == 0, the first tick
 * being tick 0 — and sends it PMAN_ACTIVATE_SIG (SIGCONT). A client attaches
 * (PMAN_init(..., PMAN_ATTACH), PMAN_attach(name, getpid())), sleeps in
 * sigsuspend, runs one cycle per SIGCONT and ends it with PMAN_epilogue(name).
 * Every table operation holds the semaphore (semop with SEM_UNDO, so a client
 * that dies holding it releases it).
 *
 * This API keeps CAMBADA's process globals (p_table, pman_sem_id,
 * pman_shmem_id): one "current" table per process, switched with
 * pman_save_ids()/pman_switch_id(). It is not thread-safe (neither is
 * CAMBADA's). A program serving several robots from several threads uses the
 * handle API of canhil/pman/pman_master.h, which shares this implementation.
 *
 * Return codes are CAMBADA's real ones (its header comments differ), except
 * where marked "canhil:". The deviations, all documented below and in
 * docs/pman.md:
 *  - PMAN_init returns PMAN_E_AGENT when AGENT is unset or invalid (CAMBADA
 *    asserts);
 *  - a QoS function is only ever called by the process that created the
 *    table, from its own memory: the pointer is never read from (or written
 *    to) shared memory, which any process can write (security fix);
 *  - a client of a missing master gets -18 without creating anything;
 *  - success is 0 where CAMBADA returns an error code on success
 *    (PMAN_prec_add: -2, PMAN_close(PMAN_CLLEAVE): -116);
 *  - the table is untrusted input: garbled counts, indexes, names, periods
 *    and pids are bounds-checked, never followed; a signal is never sent to a
 *    pid <= 0 (a process group), nor SIGINT to the calling process. */
#ifndef PMAN_H_INCLUDED
#define PMAN_H_INCLUDED

#include <signal.h>
#include <sys/time.h>
#include <sys/types.h>

#include "pmandefs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PMAN_ACTIVATE_SIG SIGCONT /* the signal that starts a client's cycle */

#define PMAN_ATTACH 1 /* PMAN_init: a client attaches to the master's table */
#define PMAN_NEW 0    /* PMAN_init: the master creates (or re-initialises) the table */

#define PMAN_CLFREE 0  /* PMAN_close by the master: SIGINT to the clients, remove table and semaphore */
#define PMAN_CLLEAVE 1 /* PMAN_close by a client: detach only */

#define PMAN_UPD_IMEDIATE 0x01  /* PMAN_QoSupd: apply now (CAMBADA's spelling) */
#define PMAN_UPD_ONNEXTACT 0x02 /* PMAN_QoSupd: apply at the next activation */
#define PMAN_UPD_PERIOD 0x04    /* PMAN_msgupd: change the period */
#define PMAN_UPD_PHASE 0x08     /* PMAN_msgupd: change the phase */
#define PMAN_UPD_DEADLINE 0x10  /* PMAN_msgupd: change the deadline */

#define PROC_TABLE_SIZE 20 /* slots in the table */
#define PNAME_LEN 32       /* longest process name; names are char[PNAME_LEN + 1] */
#define PMAN_NOPID 0       /* PROC_id of a registered process no client has attached to */
#define PMAN_NOINDEX (-1)  /* an unused PROC_succ_index entry */
#define PMAN_MAX_PRED 5    /* predecessors per process */
#define PMAN_MAX_SUCC 5    /* successors per process */
#define PMAN_NOPENDACT 0
#define PMAN_PENDACT 1

/* PROC_status */
#define PROC_S_EMPTY 0 /* free slot */
#define PROC_S_ACTIV 1 /* due this tick, not yet signalled */
#define PROC_S_READY 2 /* signalled; its cycle runs until its epilogue */
#define PROC_S_IDLE 3  /* registered, or its last cycle ended (epilogue) */
#define PROC_S_PEND 4  /* due, but waiting for a predecessor's epilogue */

#define PMAN_TRACE             /* the table carries the event trace (part of its layout) */
#define PMAN_TRACE_SIZE 10000  /* events in the trace ring */
#define MAX_MASTER_INSTANCE 40 /* masters pman_save_ids()/pman_switch_id() can hold */

/* canhil: codes CAMBADA does not have. */
#define PMAN_E_NOMEM (-4)  /* PMAN_init: no memory for this process's bookkeeping */
#define PMAN_E_ARG (-5)    /* a bad argument: name, period, pid, key 0, flag (details at each function) */
#define PMAN_E_AGENT (-10) /* PMAN_init: AGENT unset, not a number >= 0, or the key overflows */

/* One trace event; etype 'R' (release: SIGCONT sent) or 'E' (epilogue). */
typedef struct {
  int pindex; /* slot index */
  int etype;
  struct timeval etime;
} PROC_TRACE_DATA;

/* One slot (x86_64: 312 bytes; offsets in docs/pman.md and tests/pman). */
typedef struct {
  char PROC_name[PNAME_LEN + 1];                     /* "" = free slot */
  pid_t PROC_id;                                     /* the attached client, or PMAN_NOPID */
  int PROC_period;                                   /* in ticks, > 0 */
  int PROC_phase;                                    /* in ticks */
  int PROC_deadline;                                 /* stored, never evaluated (see PROC_ndm) */
  char PROC_pred_name[PMAN_MAX_PRED][PNAME_LEN + 1]; /* predecessors' names */
  int PROC_succ_index[PMAN_MAX_SUCC];                /* successors' slots, or PMAN_NOINDEX */
  unsigned long PROC_pred_mask;                      /* bit i: slot i is a predecessor */
  unsigned long PROC_pred_met;                       /* bit i: slot i ended a cycle since the last release */
  int PROC_qosdata;                                  /* byte offset of this slot's QoS data from the table's start */
  char PROC_qosupdflag;                              /* QoS data to apply at the next activation */
  struct timeval PROC_last_start;                    /* when the last SIGCONT was sent (gettimeofday) */
  struct timeval PROC_last_finish;                   /* when the last epilogue came (gettimeofday) */
  int PROC_status;                                   /* PROC_S_* */
  unsigned int PROC_nact;                            /* activations (SIGCONTs delivered) */
  unsigned int PROC_ndm;                             /* deadline misses: only the handle API counts them */
} PROC_TYPE;

/* The table at the start of the segment (x86_64: 246272 bytes); the QoS data
 * follows it, PROC_TABLE_SIZE slots of the master's QoSdata_sz bytes. */
typedef struct {
  int nprocs;            /* registered processes */
  int ticks;             /* ticks so far */
  int (*QoSupd)(int);    /* canhil: always NULL in shared memory, never called from it */
  int (*DdlnExcpt)(int); /* never used */
  PROC_TYPE proc[PROC_TABLE_SIZE];
  int evt_lastindex;  /* next trace entry to write */
  int evt_firstindex; /* oldest trace entry */
  PROC_TRACE_DATA evt_trace[PMAN_TRACE_SIZE];
} PROC_TABLE_TYPE;

/* The current table, as in CAMBADA (the names, typo included, are kept so that
 * a program compiled with CAMBADA's header links with this library). */
extern int pman_sem_id;
extern int pman_shmem_id;
extern PROC_TABLE_TYPE* p_table;
extern int pamn_sem_id_LUT[MAX_MASTER_INSTANCE];
extern int pamn_shmem_id_LUT[MAX_MASTER_INSTANCE];
extern PROC_TABLE_TYPE* pman_p_table_LUT[MAX_MASTER_INSTANCE];

/* Several masters in one process: saves the current table as master `master`
 * (0 .. MAX_MASTER_INSTANCE-1; others are ignored) / makes master `master`
 * the current table again. */
void pman_save_ids(int master);
void pman_switch_id(int master);

/* PMAN_init2 with both keys + 2*AGENT (agent N: key 0x9011 + 2N with the
 * OCAM keys). PMAN_E_AGENT if AGENT is unset, not a decimal number >= 0, or a
 * key would overflow (canhil: CAMBADA asserts); otherwise PMAN_init2's code. */
int PMAN_init(key_t shmem_pman_key, key_t sem_pman_key, void* QoSfun, int QoSdata_sz, int create_flags);

/* Makes the table under these keys the current one.
 * PMAN_NEW (master): creates the segment (mode 0666, PROC_TABLE_SIZE *
 *   QoSdata_sz bytes of QoS data after the table) or reuses one, zeroes and
 *   initialises it, creates the semaphore set (1 semaphore, mode 0666) with
 *   value 1, then asks for SCHED_FIFO at the highest priority. QoSfun, if not
 *   NULL, is an `int f(int slot)` this process calls when a slot's QoS data
 *   is to be applied (linux_sched_fifo, or NULL for none); it is kept in this
 *   process's memory only. Returns 0; -11 shmget, -12 shmat, -13 semget,
 *   -14 semctl failed; -15: SCHED_FIFO was refused (not root) — everything
 *   else is done and the table is fully usable (CAMBADA's code, kept: the
 *   caller may ignore it). An existing segment too small to be a table (e.g.
 *   a momentary one made by a CAMBADA client looking for its master) is
 *   removed and replaced.
 * PMAN_ATTACH (client): attaches the master's table. 0; -18: no master yet
 *   (no segment or no semaphore: retry later; canhil creates nothing then,
 *   CAMBADA creates an empty segment); -16: the segment is too small to be a
 *   table; -17 shmat failed.
 * PMAN_E_ARG for another flag or a key of 0 (IPC_PRIVATE); PMAN_E_NOMEM. */
int PMAN_init2(key_t shmem_pman_key, key_t sem_pman_key, void* QoSfun, int QoSdata_sz, int create_flags);

/* PMAN_CLFREE (master): waits for the semaphore, sends SIGINT to every
 *   attached client, detaches, removes the segment and the semaphore set.
 *   0; -112 shmdt, -113 removing the segment, -114 removing the semaphore
 *   failed (e.g. a client calling it after -18 against CAMBADA's library).
 * PMAN_CLLEAVE (client): detaches. 0 (canhil: CAMBADA returns -116 even on
 *   success); -115 shmdt failed.
 * -111: no current table; -116: another flag. The current table is NULL after. */
int PMAN_close(int close_flags);

/* Sends PMAN_ACTIVATE_SIG to every attached process that is due (ACTIV or
 * PEND) and whose predecessors have all ended a cycle: status READY,
 * PROC_last_start, PROC_nact + 1, trace 'R'; otherwise status PEND. A client
 * found gone (ESRCH) is deattached (PROC_id = 0, status IDLE, not counted as
 * an activation). PMAN_tick calls it. 0; -1: no table (or its semaphore is
 * gone or stuck). */
int PMAN_release(void);

/* Registers process p_name (1..PNAME_LEN characters) in the first free slot:
 * pid p_id (PMAN_NOPID until it attaches), period (ticks, > 0), phase,
 * deadline, its QoS data (p_QoSdata_sz bytes, cut to the slot's size; NULL
 * for none), status IDLE, counters 0. 0; -1 no table; -2 table full; -3 name
 * already registered; PMAN_E_ARG bad name, period or pid < 0 (canhil:
 * CAMBADA checks none). */
int PMAN_procadd(const char* p_name, int p_id, int p_period, int p_phase, int p_deadline, void* p_QoSdata,
                 int p_QoSdata_sz);

/* Unregisters p_name (SIGINT to its client, if attached; its precedences are
 * dropped). 0; -1 no table; -2 not registered. */
int PMAN_procdel(const char* p_name);

/* A client records its pid in its registered slot (and asks for its QoS to be
 * applied at the next activation). 0; -1 no table; -2 not registered (the
 * master must PMAN_procadd it first); PMAN_E_ARG a pid < 0. */
int PMAN_attach(const char* p_name, pid_t p_id);

/* Clears p_name's pid: no more activations. 0; -1 no table; -2 not registered. */
int PMAN_deattach(const char* p_name);

/* p_name_succ is released only after p_name_pred has ended a cycle.
 * 0 (canhil: CAMBADA returns -2 on success); -1 no table; -2 predecessor
 * not registered; -3 successor not registered; -4 no room for another
 * predecessor or successor (canhil: nothing is changed then); PMAN_E_ARG a
 * process as its own predecessor (it would never run again). */
int PMAN_prec_add(const char* p_name_pred, const char* p_name_succ);

/* Copies p_name's QoS data (cut to its slot) and applies it: when_flag
 * PMAN_UPD_IMEDIATE calls the master's QoS function now — only in the master
 * (canhil: in a client it falls back to PMAN_UPD_ONNEXTACT; CAMBADA would
 * call whatever pointer the table holds) — PMAN_UPD_ONNEXTACT at the next
 * activation. 0; -1 no table; -2 not registered; -3 bad when_flag. */
int PMAN_QoSupd(const char* p_name, void* QoSdata, int QoSdata_sz, char when_flag);

/* Changes the attributes selected by which_flag (PMAN_UPD_PERIOD if p_period
 * > 0, PMAN_UPD_PHASE if p_phase >= 0, PMAN_UPD_DEADLINE if p_deadline > 0).
 * 0; -1 no table; -2 not registered. */
int PMAN_msgupd(const char* p_name, int p_period, int p_phase, int p_deadline, char which_flag);

/* A client's cycle ended: status IDLE, PROC_last_finish, trace 'E'; its
 * successors may then be released. Async-signal-safe (the CAMBADA agent calls
 * it from its SIGCONT handler). 0; -1 no table; -2 not registered. */
int PMAN_epilogue(const char* p_name);

/* Iterates over the registered slots: reset_flag != 0 restarts at slot 0.
 * Copies the next registered slot into *pdata (names NUL-terminated) and
 * returns 0; 1 at the end; -1 no table; -2 pdata NULL. One iterator per
 * process, as in CAMBADA. */
int PMAN_query(PROC_TYPE* pdata, int reset_flag);

/* Prints the table / its precedences on stdout. 0; -1 no table. */
int PMAN_print(void);
int PMAN_print_prec(void);

/* Writes the trace to "<unix time>-trace.txt" in the working directory and
 * empties it. 0; -1 no table; -2 trace empty; -3 the file could not be
 * written (canhil: CAMBADA returns 0). */
int PMAN_trace_save(void);

/* One tick: every attached process due at this tick becomes ACTIV (its
 * pending QoS applied by the master's QoS function), the tick count advances,
 * then they are released (PMAN_release; canhil: in the same critical section).
 * An unfinished process is activated again; deadlines are not evaluated here
 * (the handle API counts misses). 0; -1: no table (or its semaphore is gone
 * or stuck). */
int PMAN_tick(void);

/* The stock QoS function: SCHED_FIFO for the slot's pid at the priority in
 * the int at its QoS data. 0; -3 sched_setscheduler failed (not root);
 * -1 no table, bad slot or no QoS data. Use it as PMAN_init's QoSfun. */
int linux_sched_fifo(int pindex);

#ifdef __cplusplus
}
#endif

#endif
