/* PMan's one implementation: the table in System V shared memory, its
 * semaphore, the scheduling rule. pman.c (CAMBADA's API) and pman_master.c
 * (handles) are thin layers over it. The table is writable by any process
 * (mode 0666, as CAMBADA's), so everything read from it is checked before it
 * is used as an index, a length, a divisor or a pid. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): semtimedop, SHM_DEST
#include "pman_core.h"

#include <errno.h>
#include <limits.h>
#include <sched.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/ipc.h>
#include <sys/sem.h>
#include <sys/shm.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#if defined(__x86_64__)
/* CAMBADA's table as built by gcc on x86_64 (docs/pman.md has every offset). */
_Static_assert(sizeof(PROC_TYPE) == 312, "PROC_TYPE must match CAMBADA's layout");
_Static_assert(offsetof(PROC_TYPE, PROC_qosdata) == 256, "PROC_TYPE must match CAMBADA's layout");
_Static_assert(offsetof(PROC_TYPE, PROC_ndm) == 304, "PROC_TYPE must match CAMBADA's layout");
_Static_assert(sizeof(PROC_TABLE_TYPE) == 246272, "PROC_TABLE_TYPE must match CAMBADA's layout");
_Static_assert(offsetof(PROC_TABLE_TYPE, evt_trace) == 6272, "PROC_TABLE_TYPE must match CAMBADA's layout");
#endif

#define TABLE_BYTES sizeof(PROC_TABLE_TYPE)

union pman_semun { /* semctl's fourth argument; the caller defines it on Linux */
  int val;
  struct semid_ds* buf;
  unsigned short* array;
};

static _Thread_local pman_view* g_qos_view;

pman_view* pman_core_qos_view(void) { return g_qos_view; }

/* ---- the semaphore: SEM_UNDO, so a process that dies holding it gives it back */

int pman_core_lock(pman_view* v) {
  if (v->creator && !v->published) return 0; /* set-up: the semaphore is 0 and the table is the creator's */
  struct sembuf op = {.sem_num = 0, .sem_op = -1, .sem_flg = SEM_UNDO};
  const struct timespec timeout = {.tv_sec = 1, .tv_nsec = 0};
  for (;;) {
    const int r = v->timed_lock ? semtimedop(v->sem_id, &op, 1, &timeout) : semop(v->sem_id, &op, 1);
    if (r == 0) return 0;
    if (errno != EINTR) break;
  }
  v->counters.lock_failures++;
  return -1;
}

void pman_core_unlock(pman_view* v) {
  if (v->creator && !v->published) return;
  struct sembuf op = {.sem_num = 0, .sem_op = 1, .sem_flg = SEM_UNDO};
  while (semop(v->sem_id, &op, 1) != 0 && errno == EINTR) {
  }
}

/* ---- names: the table's may lack their NUL; ours are 1..PNAME_LEN characters */

static size_t name_length(const char* name) { return name == NULL ? 0 : strnlen(name, PNAME_LEN + 1); }

static int valid_name(const char* name) {
  const size_t n = name_length(name);
  return n > 0 && n <= PNAME_LEN;
}


static int slot_is(const PROC_TYPE* p, const char* name, size_t n) {
  return memcmp(p->PROC_name, name, n) == 0 && p->PROC_name[n] == '\0';
}

static int find_slot(const PROC_TABLE_TYPE* t, const char* name) {
  if (!valid_name(name)) return -1;
  const size_t n = name_length(name);
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    if (slot_is(&t->proc[i], name, n)) return i;
  }
  return -1;
}

static void set_name(char dst[PNAME_LEN + 1], const char* name) {
  memset(dst, 0, PNAME_LEN + 1);
  memcpy(dst, name, name_length(name)); /* callers pass valid names: at most PNAME_LEN */
}

static void count_used(PROC_TABLE_TYPE* t) {
  int n = 0;
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) n += slot_used(&t->proc[i]);
  t->nprocs = n;
}

static unsigned long slot_bit(int i) { return 1UL << (unsigned)i; }

/* A copy of a slot safe to print and compare: every string NUL-terminated. */
void pman_core_copy_slot(PROC_TYPE* out, const PROC_TYPE* p) {
  memcpy(out, p, sizeof *out);
  out->PROC_name[PNAME_LEN] = '\0';
  for (int j = 0; j < PMAN_MAX_PRED; ++j) out->PROC_pred_name[j][PNAME_LEN] = '\0';
}

/* The QoS bytes of slot i inside the segment, and how many (the master's slot
 * size, cut at the segment's end); NULL if its offset points elsewhere. */
static unsigned char* qos_area(pman_view* v, int i, size_t* avail) {
  const int off = v->table->proc[i].PROC_qosdata;
  if (v->qos_slot == 0 || off < (int)TABLE_BYTES || (size_t)off >= v->seg_size) return NULL;
  const size_t left = v->seg_size - (size_t)off;
  *avail = v->qos_slot < left ? v->qos_slot : left;
  return (unsigned char*)v->table + off;
}

static void call_qos(pman_view* v, int i) {
  pman_view* const outer = g_qos_view;
  g_qos_view = v;
  (void)v->qos_fn(i);
  g_qos_view = outer;
}

static void trace_event(pman_view* v, int slot, int type, struct timeval when) {
  PROC_TABLE_TYPE* t = v->table;
  int last = t->evt_lastindex;
  int first = t->evt_firstindex;
  if (last < 0 || last >= PMAN_TRACE_SIZE || first < 0 || first >= PMAN_TRACE_SIZE) {
    v->counters.bad_entries++; /* garbled (or CAMBADA's unwrapped first index): start the ring again */
    last = first = 0;
  }
  t->evt_trace[last].pindex = slot;
  t->evt_trace[last].etype = type;
  t->evt_trace[last].etime = when;
  last = (last + 1) % PMAN_TRACE_SIZE;
  if (last == first) first = (first + 1) % PMAN_TRACE_SIZE;
  t->evt_lastindex = last;
  t->evt_firstindex = first;
}

/* A free slot: no name, no pid, no precedences, zero statistics. */
static void clear_slot(pman_view* v, int i) {
  PROC_TYPE* p = &v->table->proc[i];
  const int qos_offset = v->creator ? (int)(TABLE_BYTES + (size_t)i * v->qos_slot) : p->PROC_qosdata;
  memset(p, 0, sizeof *p);
  p->PROC_id = PMAN_NOPID;
  for (int j = 0; j < PMAN_MAX_SUCC; ++j) p->PROC_succ_index[j] = PMAN_NOINDEX;
  p->PROC_qosdata = qos_offset;
  p->PROC_status = PROC_S_EMPTY;
}

/* SIGINT (or another signal) to every attached client; never to a process
 * group (pid < 0) nor to this process. */
static void signal_clients(pman_view* v, int sig) {
  const pid_t me = getpid();
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    const pid_t pid = v->table->proc[i].PROC_id;
    if (pid == PMAN_NOPID || pid == me) continue;
    if (pid < 0) {
      v->counters.bad_entries++;
      continue;
    }
    (void)kill(pid, sig);
  }
}

/* ---- set-up */

static int shmat_failed(const void* mem) { return (intptr_t)mem == -1; }

static void init_table(pman_view* v) {
  memset(v->table, 0, v->seg_size); /* the QoS area too; QoSupd and DdlnExcpt stay NULL */
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) clear_slot(v, i);
}

int pman_core_create(pman_view* v, key_t shm_key, key_t sem_key, int qos_size, pman_qos_fn qos_fn) {
  memset(v, 0, sizeof *v);
  v->shm_id = v->sem_id = -1;
  v->creator = 1;
  v->qos_fn = qos_fn;
  v->qos_slot = qos_size > 0 ? (size_t)qos_size : 0;
  if (v->qos_slot > (INT_MAX - TABLE_BYTES) / PROC_TABLE_SIZE) return -11; /* offsets are ints */
  const size_t size = TABLE_BYTES + PROC_TABLE_SIZE * v->qos_slot;
  for (int attempt = 0;; ++attempt) {
    int id = shmget(shm_key, size, 0666 | IPC_CREAT);
    if (id < 0 && errno == EINVAL) {
      /* A smaller segment holds the key; it cannot be a table for this master
       * (e.g. a CAMBADA client's momentary one, made while looking for its
       * master): replace it. */
      const int old = shmget(shm_key, 0, 0);
      if (old >= 0 && shmctl(old, IPC_RMID, NULL) == 0) id = shmget(shm_key, size, 0666 | IPC_CREAT);
    }
    if (id < 0) return -11;
    void* mem = shmat(id, NULL, 0);
    if (shmat_failed(mem)) return -12;
    struct shmid_ds ds;
    v->table = (PROC_TABLE_TYPE*)mem;
    v->shm_id = id;
    v->seg_size = shmctl(id, IPC_STAT, &ds) == 0 && ds.shm_segsz > size ? ds.shm_segsz : size;
    init_table(v);
    const int sem = semget(sem_key, 1, 0666 | IPC_CREAT);
    union pman_semun held = {.val = 0}; /* clients that find it wait until pman_core_publish */
    const int code = sem < 0 ? -13 : semctl(sem, 0, SETVAL, held) != 0 ? -14 : 0;
    if (code != 0) {
      (void)shmdt(mem);
      (void)shmctl(id, IPC_RMID, NULL);
      v->table = NULL;
      return code;
    }
    v->sem_id = sem;
    /* A CAMBADA client that looked between our shmget and semget gave up
     * (-18) and removed the segment (its PMAN_close(PMAN_CLFREE)). The
     * semaphore exists now, so clients wait instead: make the segment again. */
    if (attempt < 3 && shmctl(id, IPC_STAT, &ds) == 0 && (ds.shm_perm.mode & SHM_DEST) != 0) {
      (void)shmdt(mem);
      v->table = NULL;
      continue;
    }
    return 0;
  }
}

int pman_core_publish(pman_view* v) {
  if (v->table == NULL) return -1;
  if (v->published) return 0;
  union pman_semun open = {.val = 1};
  if (semctl(v->sem_id, 0, SETVAL, open) != 0) return -14;
  v->published = 1;
  return 0;
}

int pman_core_attach_table(pman_view* v, key_t shm_key, key_t sem_key) {
  memset(v, 0, sizeof *v);
  v->shm_id = v->sem_id = -1;
  const int id = shmget(shm_key, TABLE_BYTES, 0666); /* never created here: that is the master's job */
  if (id < 0) return errno == ENOENT ? -18 : -16;
  const int sem = semget(sem_key, 1, 0666);
  if (sem < 0) return -18; /* the master is still setting up, or gone */
  void* mem = shmat(id, NULL, 0);
  if (shmat_failed(mem)) return -17;
  struct shmid_ds ds;
  v->table = (PROC_TABLE_TYPE*)mem;
  v->shm_id = id;
  v->sem_id = sem;
  v->seg_size = shmctl(id, IPC_STAT, &ds) == 0 && ds.shm_segsz > TABLE_BYTES ? ds.shm_segsz : TABLE_BYTES;
  v->qos_slot = (v->seg_size - TABLE_BYTES) / PROC_TABLE_SIZE;
  return 0;
}

int pman_core_close(pman_view* v, int flags) {
  if (v->table == NULL) return -111;
  if (flags == PMAN_CLLEAVE) {
    if (shmdt(v->table) != 0) return -115;
    v->table = NULL;
    return 0;
  }
  if (flags != PMAN_CLFREE) return -116;
  const int locked = pman_core_lock(v) == 0; /* wait for an operation under way (never forever: the table goes) */
  signal_clients(v, SIGINT);
  int code = 0;
  if (shmdt(v->table) != 0) {
    code = -112;
  } else {
    v->table = NULL;
    if (shmctl(v->shm_id, IPC_RMID, NULL) != 0)
      code = -113;
    else if (semctl(v->sem_id, 0, IPC_RMID) != 0)
      code = -114;
  }
  if (code != 0 && locked) pman_core_unlock(v);
  return code;
}

/* ---- registration */

int pman_core_procadd(pman_view* v, const char* name, pid_t pid, int period, int phase, int deadline, const void* qos,
                      int qos_size) {
  if (v->table == NULL) return -1;
  if (!valid_name(name) || period <= 0 || pid < 0) return PMAN_E_ARG;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  const size_t n = name_length(name);
  int slot = -1;
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    if (!slot_used(&t->proc[i])) {
      if (slot < 0) slot = i;
    } else if (slot_is(&t->proc[i], name, n)) {
      pman_core_unlock(v);
      return -3;
    }
  }
  if (slot < 0) {
    pman_core_unlock(v);
    return -2;
  }
  clear_slot(v, slot);
  PROC_TYPE* p = &t->proc[slot];
  set_name(p->PROC_name, name);
  p->PROC_id = pid;
  p->PROC_period = period;
  p->PROC_phase = phase;
  p->PROC_deadline = deadline;
  size_t avail = 0;
  unsigned char* area = qos_area(v, slot, &avail);
  if (area != NULL && qos != NULL && qos_size > 0) {
    memcpy(area, qos, (size_t)qos_size < avail ? (size_t)qos_size : avail);
  }
  p->PROC_qosupdflag = 1;
  p->PROC_status = PROC_S_IDLE;
  count_used(t);
  pman_core_unlock(v);
  return 0;
}

int pman_core_procdel(pman_view* v, const char* name) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  const int i = find_slot(t, name);
  if (i < 0) {
    pman_core_unlock(v);
    return -2;
  }
  const pid_t pid = t->proc[i].PROC_id;
  if (pid > 0 && pid != getpid()) (void)kill(pid, SIGINT);
  const size_t n = name_length(name);
  for (int k = 0; k < PROC_TABLE_SIZE; ++k) { /* nobody waits for it, nobody is waited for by it */
    PROC_TYPE* other = &t->proc[k];
    for (int j = 0; j < PMAN_MAX_SUCC; ++j) {
      if (other->PROC_succ_index[j] == i) other->PROC_succ_index[j] = PMAN_NOINDEX;
    }
    for (int j = 0; j < PMAN_MAX_PRED; ++j) {
      if (memcmp(other->PROC_pred_name[j], name, n) == 0 && other->PROC_pred_name[j][n] == '\0') {
        memset(other->PROC_pred_name[j], 0, PNAME_LEN + 1);
      }
    }
    other->PROC_pred_mask &= ~slot_bit(i);
    other->PROC_pred_met &= ~slot_bit(i);
  }
  clear_slot(v, i);
  count_used(t);
  pman_core_unlock(v);
  return 0;
}

int pman_core_set_pid(pman_view* v, const char* name, pid_t pid) {
  if (v->table == NULL) return -1;
  if (pid < 0) return PMAN_E_ARG;
  if (pman_core_lock(v) != 0) return -1;
  const int i = find_slot(v->table, name);
  if (i >= 0) {
    v->table->proc[i].PROC_id = pid;
    if (pid != PMAN_NOPID) v->table->proc[i].PROC_qosupdflag = 1; /* its QoS applies at its next activation */
  }
  pman_core_unlock(v);
  return i >= 0 ? 0 : -2;
}

int pman_core_prec_add(pman_view* v, const char* pred, const char* succ) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  const int s = find_slot(t, succ);
  const int p = s < 0 ? -1 : find_slot(t, pred);
  int code = s < 0 ? -3 : p < 0 ? -2 : p == s ? PMAN_E_ARG : 0;
  int name_at = -1;
  int succ_at = -1;
  for (int j = 0; code == 0 && j < PMAN_MAX_PRED && name_at < 0; ++j) {
    if (t->proc[s].PROC_pred_name[j][0] == '\0') name_at = j;
  }
  for (int j = 0; code == 0 && j < PMAN_MAX_SUCC && succ_at < 0; ++j) {
    if (t->proc[p].PROC_succ_index[j] == PMAN_NOINDEX) succ_at = j;
  }
  if (code == 0 && (name_at < 0 || succ_at < 0)) code = -4;
  if (code == 0) {
    set_name(t->proc[s].PROC_pred_name[name_at], pred);
    t->proc[p].PROC_succ_index[succ_at] = s;
    t->proc[s].PROC_pred_met = 0;
    t->proc[s].PROC_pred_mask |= slot_bit(p);
  }
  pman_core_unlock(v);
  return code;
}

int pman_core_qos_update(pman_view* v, const char* name, const void* qos, int qos_size, char when) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  const int i = find_slot(v->table, name);
  int code = i < 0 ? -2 : (when != PMAN_UPD_IMEDIATE && when != PMAN_UPD_ONNEXTACT) ? -3 : 0;
  if (code == 0) {
    PROC_TYPE* p = &v->table->proc[i];
    size_t avail = 0;
    unsigned char* area = qos_area(v, i, &avail);
    if (area != NULL && qos != NULL && qos_size > 0) {
      memcpy(area, qos, (size_t)qos_size < avail ? (size_t)qos_size : avail);
    }
    if (when == PMAN_UPD_IMEDIATE && v->creator) {
      if (v->qos_fn != NULL) call_qos(v, i);
      p->PROC_qosupdflag = 0;
    } else {
      p->PROC_qosupdflag = 1; /* a client cannot run the master's function: the master applies it */
    }
  }
  pman_core_unlock(v);
  return code;
}

int pman_core_msg_update(pman_view* v, const char* name, int period, int phase, int deadline, char which) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  const int i = find_slot(v->table, name);
  if (i >= 0) {
    PROC_TYPE* p = &v->table->proc[i];
    if ((which & PMAN_UPD_PERIOD) && period > 0) p->PROC_period = period;
    if ((which & PMAN_UPD_PHASE) && phase >= 0) p->PROC_phase = phase;
    if ((which & PMAN_UPD_DEADLINE) && deadline > 0) p->PROC_deadline = deadline;
  }
  pman_core_unlock(v);
  return i >= 0 ? 0 : -2;
}

/* ---- the cycle */

/* Signals every due process whose predecessors are done. The semaphore is held. */
static int release_locked(pman_view* v) {
  PROC_TABLE_TYPE* t = v->table;
  int released = 0;
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    PROC_TYPE* p = &t->proc[i];
    const pid_t pid = p->PROC_id;
    if (pid == PMAN_NOPID || (p->PROC_status != PROC_S_ACTIV && p->PROC_status != PROC_S_PEND)) continue;
    if (pid < 0) { /* kill(-n) would signal a whole process group */
      v->counters.bad_entries++;
      p->PROC_status = PROC_S_IDLE;
      continue;
    }
    if (p->PROC_pred_mask != p->PROC_pred_met) {
      p->PROC_status = PROC_S_PEND;
      continue;
    }
    p->PROC_pred_met = 0;
    if (kill(pid, PMAN_ACTIVATE_SIG) != 0) {
      if (errno == ESRCH) { /* the client died: deattach it */
        p->PROC_id = PMAN_NOPID;
        v->counters.dead_clients++;
      } else {
        v->counters.signal_failures++;
      }
      p->PROC_status = PROC_S_IDLE;
      continue;
    }
    gettimeofday(&p->PROC_last_start, NULL);
    trace_event(v, i, 'R', p->PROC_last_start);
    p->PROC_status = PROC_S_READY;
    p->PROC_nact++;
    v->counters.activations++;
    ++released;
  }
  return released;
}

int pman_core_release(pman_view* v) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  const int released = release_locked(v);
  pman_core_unlock(v);
  return released;
}

int pman_core_tick(pman_view* v) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  const long long now = t->ticks;
  int due = 0;
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    PROC_TYPE* p = &t->proc[i];
    if (p->PROC_id == PMAN_NOPID) continue;
    if (p->PROC_period <= 0 || p->PROC_id < 0) { /* a divisor of 0 would crash the master */
      v->counters.bad_entries++;
      continue;
    }
    if ((now - p->PROC_phase) % p->PROC_period != 0) continue;
    if (v->count_misses && (p->PROC_status == PROC_S_READY || p->PROC_status == PROC_S_ACTIV)) {
      p->PROC_ndm++; /* due again before its last cycle ended */
      v->counters.deadline_misses++;
    }
    if (p->PROC_qosupdflag) {
      if (v->creator && v->qos_fn != NULL) call_qos(v, i);
      p->PROC_qosupdflag = 0;
    }
    p->PROC_status = PROC_S_ACTIV;
    due = 1;
  }
  t->ticks = (int)((unsigned)t->ticks + 1u); /* wraps after 2^31 ticks, never overflows */
  v->counters.ticks++;
  const int released = due ? release_locked(v) : 0;
  pman_core_unlock(v);
  return released;
}

int pman_core_epilogue(pman_view* v, const char* name) {
  if (v->table == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  PROC_TABLE_TYPE* t = v->table;
  const int i = find_slot(t, name);
  if (i >= 0) {
    PROC_TYPE* p = &t->proc[i];
    p->PROC_status = PROC_S_IDLE;
    gettimeofday(&p->PROC_last_finish, NULL);
    trace_event(v, i, 'E', p->PROC_last_finish);
    int successors = 0;
    for (int j = 0; j < PMAN_MAX_SUCC; ++j) {
      const int s = p->PROC_succ_index[j];
      if (s == PMAN_NOINDEX) continue;
      if (s < 0 || s >= PROC_TABLE_SIZE) {
        v->counters.bad_entries++;
        continue;
      }
      t->proc[s].PROC_pred_met |= slot_bit(i);
      successors = 1;
    }
    if (successors) (void)release_locked(v);
  }
  pman_core_unlock(v);
  return i >= 0 ? 0 : -2;
}

/* ---- queries (the reports are in pman_report.c) */

int pman_core_query_name(pman_view* v, const char* name, PROC_TYPE* out) {
  if (v->table == NULL || out == NULL) return -1;
  if (pman_core_lock(v) != 0) return -1;
  const int i = find_slot(v->table, name);
  if (i >= 0) pman_core_copy_slot(out, &v->table->proc[i]);
  pman_core_unlock(v);
  return i >= 0 ? 0 : -2;
}

int pman_core_query_next(pman_view* v, int* index, PROC_TYPE* out) {
  if (v->table == NULL) return -1;
  if (*index < 0) *index = 0;
  if (*index >= PROC_TABLE_SIZE) return 1;
  if (pman_core_lock(v) != 0) return -1;
  int found = -1;
  for (int i = *index; i < PROC_TABLE_SIZE && found < 0; ++i) {
    if (slot_used(&v->table->proc[i])) found = i;
  }
  if (found >= 0) pman_core_copy_slot(out, &v->table->proc[found]);
  pman_core_unlock(v);
  *index = found >= 0 ? found + 1 : PROC_TABLE_SIZE;
  return found >= 0 ? 0 : 1;
}

int pman_core_sched_fifo(pman_view* v, int pindex) {
  if (v == NULL || v->table == NULL || pindex < 0 || pindex >= PROC_TABLE_SIZE) return -1;
  size_t avail = 0;
  const unsigned char* area = qos_area(v, pindex, &avail);
  const pid_t pid = v->table->proc[pindex].PROC_id;
  if (area == NULL || avail < sizeof(int) || pid <= 0) return -1;
  struct sched_param param;
  memset(&param, 0, sizeof param);
  memcpy(&param.sched_priority, area, sizeof(int));
  return sched_setscheduler(pid, SCHED_FIFO, &param) == 0 ? 0 : -3;
}
