/* CAMBADA's PMan API (pman.h) over pman_core: the process globals name the
 * current table; what this process knows about each table it opened (is it
 * the creator, its QoS function, its size) is kept here, found by the
 * table's address, so pman_switch_id() carries it along. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): the POSIX/GNU feature macro
#include "pman.h"

#include <errno.h>
#include <limits.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ipc.h>

#include "canhil/base/second_set.h"
#include "canhil/pman/pman_master.h"
#include "pman_core.h"

PMAN_EXPORT int pman_sem_id = -1;
PMAN_EXPORT int pman_shmem_id = -1;
PMAN_EXPORT PROC_TABLE_TYPE* p_table = NULL;
PMAN_EXPORT int pamn_sem_id_LUT[MAX_MASTER_INSTANCE];
PMAN_EXPORT int pamn_shmem_id_LUT[MAX_MASTER_INSTANCE];
PMAN_EXPORT PROC_TABLE_TYPE* pman_p_table_LUT[MAX_MASTER_INSTANCE];

typedef struct opened_table {
  pman_view view;
  struct opened_table* next;
} opened_table;

static opened_table* g_opened; /* every table PMAN_init2 opened and PMAN_close has not closed */
static pman_view g_unknown;    /* a current table this process did not open (set by hand) */
static int g_query_index;      /* PMAN_query's iterator, one per process as in CAMBADA */

/* The view of the current table. No allocation, no lock: PMAN_epilogue runs
 * in a client's signal handler. */
static pman_view* current(void) {
  for (opened_table* t = g_opened; t != NULL; t = t->next) {
    if (p_table != NULL && t->view.table == p_table) {
      t->view.sem_id = pman_sem_id;
      t->view.shm_id = pman_shmem_id;
      return &t->view;
    }
  }
  memset(&g_unknown, 0, sizeof g_unknown); /* trusted: the table only, no QoS area, not the creator */
  g_unknown.table = p_table;
  g_unknown.sem_id = pman_sem_id;
  g_unknown.shm_id = pman_shmem_id;
  g_unknown.seg_size = sizeof(PROC_TABLE_TYPE);
  return &g_unknown;
}

/* After a table is detached: no pointer to it stays anywhere. */
static void forget(PROC_TABLE_TYPE* table) {
  for (opened_table** link = &g_opened; *link != NULL;) {
    opened_table* t = *link;
    if (t->view.table == NULL || t->view.table == table) {
      *link = t->next;
      free(t);
    } else {
      link = &t->next;
    }
  }
  for (int m = 0; m < MAX_MASTER_INSTANCE; ++m) {
    if (pman_p_table_LUT[m] == table) {
      pman_p_table_LUT[m] = NULL;
      pamn_sem_id_LUT[m] = pamn_shmem_id_LUT[m] = -1;
    }
  }
  if (p_table == table) {
    p_table = NULL;
    pman_sem_id = pman_shmem_id = -1;
  }
}

PMAN_EXPORT void pman_save_ids(int master) {
  if (master < 0 || master >= MAX_MASTER_INSTANCE) return;
  pamn_sem_id_LUT[master] = pman_sem_id;
  pamn_shmem_id_LUT[master] = pman_shmem_id;
  pman_p_table_LUT[master] = p_table;
}

PMAN_EXPORT void pman_switch_id(int master) {
  if (master < 0 || master >= MAX_MASTER_INSTANCE) return;
  pman_sem_id = pamn_sem_id_LUT[master];
  pman_shmem_id = pamn_shmem_id_LUT[master];
  p_table = pman_p_table_LUT[master];
}

PMAN_EXPORT int PMAN_init(key_t shmem_pman_key, key_t sem_pman_key, void* QoSfun, int QoSdata_sz, int create_flags) {
  const char* text = getenv("AGENT");
  if (text == NULL || *text == '\0') {
    fprintf(stderr, "PMan: AGENT is not set: set AGENT=<robot number> (keys are 0x9011 + 2*AGENT)\n");
    return PMAN_E_AGENT;
  }
  char* end = NULL;
  errno = 0;
  const long agent = strtol(text, &end, 10);
  /* A process of a second team (SECOND_RTDB set, and not "0", as for its RTDB set). */
  const long long set_offset = canhil_second_set_from_environment() ? CANHIL_PMAN_SECOND_SET_OFFSET : 0;
  const long long shm_key = (long long)shmem_pman_key + 2LL * agent + set_offset;
  const long long sem_key = (long long)sem_pman_key + 2LL * agent + set_offset;
  if (errno != 0 || *end != '\0' || agent < 0 || shm_key > INT_MAX || sem_key > INT_MAX) {
    fprintf(stderr, "PMan: AGENT=%s is not a robot number (0, 1, 2, ...)\n", text);
    return PMAN_E_AGENT;
  }
  return PMAN_init2((key_t)shm_key, (key_t)sem_key, QoSfun, QoSdata_sz, create_flags);
}

PMAN_EXPORT int PMAN_init2(key_t shmem_pman_key, key_t sem_pman_key, void* QoSfun, int QoSdata_sz, int create_flags) {
  if (shmem_pman_key == IPC_PRIVATE || sem_pman_key == IPC_PRIVATE) return PMAN_E_ARG;
  if (create_flags != PMAN_NEW && create_flags != PMAN_ATTACH) return PMAN_E_ARG;
  opened_table* t = calloc(1, sizeof *t);
  if (t == NULL) return PMAN_E_NOMEM;
  int code = 0;
  if (create_flags == PMAN_NEW) {
    pman_qos_fn qos_fn = NULL; /* kept here, in this process; never put in shared memory */
    _Static_assert(sizeof qos_fn == sizeof QoSfun, "a function pointer travels in PMAN_init's void*");
    memcpy(&qos_fn, &QoSfun, sizeof qos_fn);
    code = pman_core_create(&t->view, shmem_pman_key, sem_pman_key, QoSdata_sz, qos_fn);
    if (code == 0) {
      code = pman_core_publish(&t->view);
      if (code != 0) (void)pman_core_close(&t->view, PMAN_CLFREE);
    }
  } else {
    code = pman_core_attach_table(&t->view, shmem_pman_key, sem_pman_key);
  }
  if (code != 0) {
    free(t);
    return code;
  }
  t->next = g_opened;
  g_opened = t;
  p_table = t->view.table;
  pman_sem_id = t->view.sem_id;
  pman_shmem_id = t->view.shm_id;
  if (create_flags == PMAN_NEW) {
    /* CAMBADA's master runs SCHED_FIFO at the top priority. Refused (not
     * root): -15, as CAMBADA — but the table is complete and in use. */
    struct sched_param param;
    memset(&param, 0, sizeof param);
    param.sched_priority = sched_get_priority_max(SCHED_FIFO);
    if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) return -15;
  }
  return 0;
}

PMAN_EXPORT int PMAN_close(int close_flags) {
  if (p_table == NULL) return -111;
  PROC_TABLE_TYPE* table = p_table;
  pman_view* v = current();
  const int code = pman_core_close(v, close_flags);
  if (v->table == NULL) forget(table);
  return code;
}

PMAN_EXPORT int PMAN_release(void) { return pman_core_release(current()) < 0 ? -1 : 0; }

PMAN_EXPORT int PMAN_procadd(const char* p_name, int p_id, int p_period, int p_phase, int p_deadline, void* p_QoSdata,
                             int p_QoSdata_sz) {
  return pman_core_procadd(current(), p_name, (pid_t)p_id, p_period, p_phase, p_deadline, p_QoSdata, p_QoSdata_sz);
}

PMAN_EXPORT int PMAN_procdel(const char* p_name) { return pman_core_procdel(current(), p_name); }

PMAN_EXPORT int PMAN_attach(const char* p_name, pid_t p_id) { return pman_core_set_pid(current(), p_name, p_id); }

PMAN_EXPORT int PMAN_deattach(const char* p_name) { return pman_core_set_pid(current(), p_name, PMAN_NOPID); }

PMAN_EXPORT int PMAN_prec_add(const char* p_name_pred, const char* p_name_succ) {
  return pman_core_prec_add(current(), p_name_pred, p_name_succ);
}

PMAN_EXPORT int PMAN_QoSupd(const char* p_name, void* QoSdata, int QoSdata_sz, char when_flag) {
  return pman_core_qos_update(current(), p_name, QoSdata, QoSdata_sz, when_flag);
}

PMAN_EXPORT int PMAN_msgupd(const char* p_name, int p_period, int p_phase, int p_deadline, char which_flag) {
  return pman_core_msg_update(current(), p_name, p_period, p_phase, p_deadline, which_flag);
}

PMAN_EXPORT int PMAN_epilogue(const char* p_name) { return pman_core_epilogue(current(), p_name); }

PMAN_EXPORT int PMAN_query(PROC_TYPE* pdata, int reset_flag) {
  if (reset_flag) g_query_index = 0;
  if (pdata == NULL) return -2;
  return pman_core_query_next(current(), &g_query_index, pdata);
}

PMAN_EXPORT int PMAN_print(void) { return pman_core_print(current()); }

PMAN_EXPORT int PMAN_print_prec(void) { return pman_core_print_prec(current()); }

PMAN_EXPORT int PMAN_trace_save(void) { return pman_core_trace_save(current()); }

PMAN_EXPORT int PMAN_tick(void) { return pman_core_tick(current()) < 0 ? -1 : 0; }

PMAN_EXPORT int linux_sched_fifo(int pindex) {
  pman_view* v = pman_core_qos_view(); /* the table whose tick is calling, else the current one */
  return pman_core_sched_fifo(v != NULL ? v : current(), pindex);
}
