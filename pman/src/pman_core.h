/* pman_core.h — the one implementation behind pman.h (CAMBADA's API over
 * process globals) and canhil/pman/pman_master.h (handles). Private. */
#ifndef CANHIL_PMAN_CORE_H
#define CANHIL_PMAN_CORE_H

#include <stddef.h>
#include <sys/types.h>

#include "canhil/pman/pman_master.h"
#include "pman.h"

#define PMAN_EXPORT __attribute__((visibility("default")))

typedef int (*pman_qos_fn)(int pindex);

/* What this process knows about one attached table. Nothing here is ever
 * read from shared memory: the table itself is untrusted. */
typedef struct {
  PROC_TABLE_TYPE* table; /* the mapping, or NULL */
  int shm_id;
  int sem_id;
  size_t seg_size;    /* bytes mapped; only the table itself is trusted when unknown */
  size_t qos_slot;    /* QoS bytes per slot (the master's QoSdata_sz) */
  pman_qos_fn qos_fn; /* the master's QoS function (creator only) */
  int creator;        /* this process created (PMAN_NEW) the table */
  int published;      /* the semaphore was opened to clients */
  int timed_lock;     /* give up waiting for the semaphore after 1 s (handle API) */
  int count_misses;   /* a tick counts deadline misses (handle API) */
  canhil_pman_counters counters;
} pman_view;

/* A table slot holds a process (its name is set). */
static inline int slot_used(const PROC_TYPE* p) { return p->PROC_name[0] != '\0'; }

/* Set-up. create: a fresh, unpublished table (semaphore 0, held by the
 * creator); publish: semaphore 1. attach: a client's mapping, -16/-17/-18. */
int pman_core_create(pman_view* v, key_t shm_key, key_t sem_key, int qos_size, pman_qos_fn qos_fn);
int pman_core_publish(pman_view* v);
int pman_core_attach_table(pman_view* v, key_t shm_key, key_t sem_key);
int pman_core_close(pman_view* v, int flags);

/* The table operations; codes as in pman.h. */
int pman_core_procadd(pman_view* v, const char* name, pid_t pid, int period, int phase, int deadline, const void* qos,
                      int qos_size);
int pman_core_procdel(pman_view* v, const char* name);
int pman_core_set_pid(pman_view* v, const char* name, pid_t pid);
int pman_core_prec_add(pman_view* v, const char* pred, const char* succ);
int pman_core_qos_update(pman_view* v, const char* name, const void* qos, int qos_size, char when);
int pman_core_msg_update(pman_view* v, const char* name, int period, int phase, int deadline, char which);
int pman_core_epilogue(pman_view* v, const char* name);
int pman_core_query_name(pman_view* v, const char* name, PROC_TYPE* out);
/* The next registered slot at or after *index (advanced past it): 0; 1 at the end. */
int pman_core_query_next(pman_view* v, int* index, PROC_TYPE* out);
/* Processes signalled (>= 0), or -1. */
int pman_core_tick(pman_view* v);
int pman_core_release(pman_view* v);

int pman_core_print(pman_view* v);
int pman_core_print_prec(pman_view* v);
int pman_core_trace_save(pman_view* v);
int pman_core_sched_fifo(pman_view* v, int pindex);

/* For pman_report.c: the semaphore (0, or -1 counted in lock_failures), and
 * a copy of a slot with every string NUL-terminated. */
int pman_core_lock(pman_view* v);
void pman_core_unlock(pman_view* v);
void pman_core_copy_slot(PROC_TYPE* out, const PROC_TYPE* p);

/* The table whose QoS function is running on this thread (for
 * linux_sched_fifo), or NULL. */
pman_view* pman_core_qos_view(void);

#endif
