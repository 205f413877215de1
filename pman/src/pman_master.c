/* canhil's PMan masters as handles (canhil/pman/pman_master.h) over
 * pman_core: one table per handle, no process globals. */
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ipc.h>

#include "canhil/pman/pman_master.h"
#include "pman_core.h"

struct canhil_pman {
  pman_view view;
};

PMAN_EXPORT canhil_pman* canhil_pman_open_master_keys(key_t shm_key, key_t sem_key, int* error) {
  int code = 0;
  canhil_pman* h = NULL;
  if (shm_key == IPC_PRIVATE || sem_key == IPC_PRIVATE) {
    code = PMAN_E_ARG;
  } else if ((h = calloc(1, sizeof *h)) == NULL) {
    code = PMAN_E_NOMEM;
  } else {
    code = pman_core_create(&h->view, shm_key, sem_key, (int)sizeof(int), NULL); /* the stock master's size */
  }
  if (code != 0) {
    free(h);
    h = NULL;
  } else {
    h->view.timed_lock = 1;
    h->view.count_misses = 1;
  }
  if (error != NULL) *error = code;
  return h;
}

PMAN_EXPORT canhil_pman* canhil_pman_open_master(int agent, int* error) {
  const long long key = SHMEM_OCAM_PMAN_KEY + 2LL * agent;
  if (agent < 0 || key > INT_MAX) {
    if (error != NULL) *error = PMAN_E_AGENT;
    return NULL;
  }
  return canhil_pman_open_master_keys((key_t)key, (key_t)key, error);
}

PMAN_EXPORT int canhil_pman_procadd(canhil_pman* h, const char* name, int period, int phase, int deadline) {
  if (h == NULL) return -1;
  const int priority = 0; /* the QoS data: nobody applies it */
  return pman_core_procadd(&h->view, name, PMAN_NOPID, period, phase, deadline, &priority, (int)sizeof priority);
}

PMAN_EXPORT int canhil_pman_procdel(canhil_pman* h, const char* name) {
  return h == NULL ? -1 : pman_core_procdel(&h->view, name);
}

PMAN_EXPORT int canhil_pman_start(canhil_pman* h) { return h == NULL ? -1 : pman_core_publish(&h->view); }

PMAN_EXPORT int canhil_pman_tick(canhil_pman* h) {
  if (h == NULL) return -1;
  const int published = pman_core_publish(&h->view);
  return published != 0 ? published : pman_core_tick(&h->view);
}

PMAN_EXPORT int canhil_pman_query(canhil_pman* h, const char* name, PROC_TYPE* out) {
  return h == NULL ? -1 : pman_core_query_name(&h->view, name, out);
}

PMAN_EXPORT canhil_pman_counters canhil_pman_get_counters(const canhil_pman* h) {
  canhil_pman_counters none;
  memset(&none, 0, sizeof none);
  return h == NULL ? none : h->view.counters;
}

PMAN_EXPORT int canhil_pman_close(canhil_pman* h) {
  if (h == NULL) return -1;
  const int code = pman_core_close(&h->view, PMAN_CLFREE);
  free(h);
  return code;
}
