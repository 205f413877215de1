/* PMan's reports: the table and its precedences on stdout, the trace to a
 * file. Everything printed comes from a copy taken under the semaphore (or,
 * for the trace, with it held), and every string and index from the table is
 * bounded first. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "pman_core.h"


/* A consistent copy of the slots, taken under the semaphore. */
static int snapshot(pman_view* v, PROC_TYPE procs[PROC_TABLE_SIZE], int* ticks) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) pman_core_copy_slot(&procs[i], &v->table->proc[i]);
  *ticks = v->table->ticks;
  pman_core_unlock(v);
  return 0;
}

static const char* status_name(int status) {
  static const char* const kNames[] = {"empty", "activ", "ready", "idle", "pend"};
  return status >= PROC_S_EMPTY && status <= PROC_S_PEND ? kNames[status] : "?";
}

int pman_core_print(pman_view* v) {
  PROC_TYPE procs[PROC_TABLE_SIZE];
  int ticks = 0;
  if (snapshot(v, procs, &ticks) != 0) return -1;
  printf("PMan table: tick %d\n", ticks);
  printf("slot %-16s %7s %6s %5s %8s %6s %8s %6s %17s %17s\n", "name", "pid", "period", "phase", "deadline", "status",
         "nact", "ndm", "last start", "last finish");
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    const PROC_TYPE* p = &procs[i];
    if (!slot_used(p)) continue;
    printf("%4d %-16s %7d %6d %5d %8d %6s %8u %6u %10lld.%06ld %10lld.%06ld\n", i, p->PROC_name, (int)p->PROC_id,
           p->PROC_period, p->PROC_phase, p->PROC_deadline, status_name(p->PROC_status), p->PROC_nact, p->PROC_ndm,
           (long long)p->PROC_last_start.tv_sec, (long)p->PROC_last_start.tv_usec,
           (long long)p->PROC_last_finish.tv_sec, (long)p->PROC_last_finish.tv_usec);
  }
  return 0;
}

int pman_core_print_prec(pman_view* v) {
  PROC_TYPE procs[PROC_TABLE_SIZE];
  int ticks = 0;
  if (snapshot(v, procs, &ticks) != 0) return -1;
  printf("PMan precedences: slot name: after {predecessors} before {successor slots} mask met status\n");
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    const PROC_TYPE* p = &procs[i];
    if (!slot_used(p)) continue;
    printf("%4d %s: after {", i, p->PROC_name);
    for (int j = 0; j < PMAN_MAX_PRED; ++j) {
      if (p->PROC_pred_name[j][0] != '\0') printf(" %s", p->PROC_pred_name[j]);
    }
    printf(" } before {");
    for (int j = 0; j < PMAN_MAX_SUCC; ++j) {
      if (p->PROC_succ_index[j] != PMAN_NOINDEX) printf(" %d", p->PROC_succ_index[j]);
    }
    printf(" } %#lx %#lx %s\n", p->PROC_pred_mask, p->PROC_pred_met, status_name(p->PROC_status));
  }
  return 0;
}

int pman_core_trace_save(pman_view* v) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  int first = t->evt_firstindex;
  const int last = t->evt_lastindex;
  int code = 0;
  if (first < 0 || first >= PMAN_TRACE_SIZE || last < 0 || last >= PMAN_TRACE_SIZE || first == last) {
    code = -2;
  } else {
    char file_name[64];
    snprintf(file_name, sizeof file_name, "%lld-trace.txt", (long long)time(NULL));
    FILE* out = fopen(file_name, "w");
    if (out == NULL) {
      code = -3;
    } else {
      fprintf(out, "name,slot,event,sec,usec\n");
      for (; first != last; first = (first + 1) % PMAN_TRACE_SIZE) {
        const PROC_TRACE_DATA* e = &t->evt_trace[first];
        const int ok = e->pindex >= 0 && e->pindex < PROC_TABLE_SIZE;
        fprintf(out, "%.*s,%d,%c,%lld,%06ld\n", PNAME_LEN, ok ? t->proc[e->pindex].PROC_name : "?", e->pindex,
                e->etype == 'R' || e->etype == 'E' ? e->etype : '?', (long long)e->etime.tv_sec,
                (long)e->etime.tv_usec);
      }
      code = fclose(out) == 0 ? 0 : -3;
    }
  }
  if (code != -2) t->evt_firstindex = t->evt_lastindex = 0;
  pman_core_unlock(v);
  return code;
}
