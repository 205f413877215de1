/* The RTDB: one System V shared-memory segment per agent, sequence-locked
 * item slots, ages from CLOCK_MONOTONIC; the item table linked in or read
 * from an rtdb.ini (rtdb_ini.c). See canhil/rtdb/rtdb.h and CAMBADA's names
 * in rtdb_api.h, rtdb_sim.h, rtdb_comm.h. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): the POSIX/GNU feature macro
#include "canhil/rtdb/rtdb.h"

#include <errno.h>
#include <limits.h>
#include <semaphore.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <time.h>
#include <unistd.h>

#include "canhil/base/second_set.h"

#include "rtdb_internal.h"
#include "rtdb_slot.h"

#define RTDB_MAGIC 0x43484C52u /* "CHLR" */
#define RTDB_VERSION 2u        /* 2: the configuration hash leaves names out */

typedef struct {
  _Atomic uint32_t magic; /* set last by the creator */
  uint32_t version;
  uint64_t config_hash;
  int32_t agent;
  int32_t creator_pid;
  int64_t created_ns;
  uint64_t total_size;
} segment_header;

static const canhil_rtdb_table* g_table = NULL; /* chosen at the first use; see table() */
static canhil_rtdb_table* g_loaded = NULL;      /* g_table when read from an rtdb.ini */
static char* g_config_file = NULL;              /* DB_set_config_file's */
static int g_table_stale = 0;                   /* DB_set_config_file since g_table was chosen */
static int g_table_failed = 0;                  /* reading it failed; only an init tries again */
/* A memory space is an agent of one of the two sets (teams): space a is
 * agent a of the first, space n_agents + a agent a of the second (CAMBADA's
 * DB_init_all(1) and SECOND_RTDB). The second set's keys and semaphores are
 * the first's plus CANHIL_RTDB_SET_STRIDE: a process of the second team may
 * equally set RTDB_KEY to the first's base plus the stride. */
#define SETS CANHIL_RTDB_SETS
static int g_me = -1;                              /* this process's memory space (DB_init) */
static int g_me_nesting = 0;                       /* DB_init calls not yet freed */
static int g_all[SETS] = {0, 0};                   /* DB_init_all calls not yet freed, per set */
static void* g_seg[SETS * CANHIL_RTDB_MAX_AGENTS]; /* attached segments, by memory space */
static int g_shmid[SETS * CANHIL_RTDB_MAX_AGENTS];
static int64_t* g_offsets = NULL; /* [segment agent][owner agent][item] -> byte offset, or -1 */
static uint64_t g_sizes[CANHIL_RTDB_MAX_AGENTS];

static int verbose(void) {
  const char* v = getenv("RTDB_VERBOSE");
  return v != NULL && v[0] == '1';
}

static int64_t monotonic_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* DB_set_clock's: stamps are g_clock(g_clock_context) + g_clock_offset. */
static int64_t (*g_clock)(void*) = NULL;
static void* g_clock_context = NULL;
static int64_t g_clock_offset = 0;

static int64_t now_ns(void) { return g_clock != NULL ? g_clock(g_clock_context) + g_clock_offset : monotonic_ns(); }

RTDB_EXPORT void DB_set_clock(int64_t (*now)(void* context), void* context) {
  g_clock = NULL;
  if (now != NULL) g_clock_offset = monotonic_ns() - now(context);
  g_clock_context = context;
  g_clock = now;
}

static int attached(void) { return g_me >= 0 || g_all[0] > 0 || g_all[1] > 0; }

/* Memory space -> agent (its layout) and set. */
static int agent_of(int space) { return space % (int)g_table->n_agents; }
static int set_of(int space) { return space / (int)g_table->n_agents; }
static int spaces(void) { return SETS * (int)g_table->n_agents; }

/* The item table: DB_set_config_file's rtdb.ini, else the linked one, else
 * (librtdb.so) $CANHIL_RTDB_INI or CONFIG_FILE. Chosen once and kept while
 * anything is attached; a failure is retried by the next init only. */
static const canhil_rtdb_table* table(int retry) {
  if (g_table_stale && !attached()) {
    canhil_rtdb_table_free(g_loaded);
    g_loaded = NULL;
    g_table = NULL;
    g_table_stale = 0;
    g_table_failed = 0;
  }
  if (g_table != NULL) return g_table;
  if (g_table_failed && !retry) return NULL;
  const canhil_rtdb_table* linked = canhil_rtdb_linked_table();
  if (g_config_file == NULL && linked != NULL) return g_table = linked;
  const char* env = getenv("CANHIL_RTDB_INI");
  const char* ini = g_config_file != NULL ? g_config_file : (env != NULL && *env != '\0' ? env : CONFIG_FILE);
  const char* names = getenv("CANHIL_RTDB_USER_H");
  char error[1024];
  g_loaded = canhil_rtdb_table_load(ini, names != NULL && *names != '\0' ? names : NULL, error, sizeof error);
  if (g_loaded == NULL) {
    g_table_failed = 1;
    fprintf(stderr, "rtdb: %s\n", error);
    if (g_config_file == NULL) {
      fprintf(stderr,
              "rtdb: (the item table is DB_set_config_file's file, else $CANHIL_RTDB_INI, else %s from the working "
              "directory)\n",
              CONFIG_FILE);
    }
    return NULL;
  }
  return g_table = g_loaded;
}

/* The heap the library keeps between calls, returned when it is unloaded
 * (dlclose) or the program ends with nothing attached (while attached, the
 * memory stays with the attachment). */
__attribute__((destructor)) static void release_heap(void) {
  if (attached()) return;
  canhil_rtdb_table_free(g_loaded);
  g_loaded = NULL;
  g_table = NULL;
  free(g_config_file);
  g_config_file = NULL;
  free(g_offsets);
  g_offsets = NULL;
}

/* What two programs must agree on to share a segment: agents, sizes and who
 * has which item (names are for people: an rtdb.ini has none). */
static uint64_t config_hash(void) {
  uint64_t h = 1469598103934665603ULL; /* FNV-1a */
  const canhil_rtdb_table* t = g_table;
#define MIX(byte) (h = (h ^ (uint8_t)(byte)) * 1099511628211ULL)
  for (int b = 0; b < 4; ++b) MIX(t->n_agents >> (8 * b));
  for (uint32_t a = 0; a < t->n_agents; ++a) {
    for (uint32_t i = 0; i < t->n_items; ++i) MIX(t->agents[a].membership[i] + 2);
  }
  for (uint32_t i = 0; i < t->n_items; ++i) {
    for (int b = 0; b < 4; ++b) MIX(t->items[i].size >> (8 * b));
  }
#undef MIX
  return h;
}

static key_t base_key(void) {
  const char* k = getenv("RTDB_KEY");
  if (k != NULL && *k != '\0') return (key_t)strtol(k, NULL, 0);
  return (key_t)(0x52400000u | ((unsigned)getuid() & 0xFFFu) << 8);
}

/* The key base of a memory space's set. */
static key_t set_key(int space) { return base_key() + (key_t)(set_of(space) * CANHIL_RTDB_SET_STRIDE); }

/* "agent 3" or "agent 3 of the second set", for messages. */
static const char* set_name(int space) { return set_of(space) == 0 ? "" : " of the second set"; }

static int64_t* offset_at(int seg, int owner, int item) {
  const uint32_t na = g_table->n_agents;
  const uint32_t ni = g_table->n_items;
  return &g_offsets[((size_t)seg * na + (size_t)owner) * ni + (size_t)item];
}

/* Lays out every segment: the agent's own items, then the shared items of each other agent. */
static int compute_layout(void) {
  const uint32_t na = g_table->n_agents;
  const uint32_t ni = g_table->n_items;
  if (na == 0 || na > CANHIL_RTDB_MAX_AGENTS) {
    fprintf(stderr, "rtdb: the configuration has %u agents; canhil supports 1 to %d\n", na, CANHIL_RTDB_MAX_AGENTS);
    return -1;
  }
  free(g_offsets);
  g_offsets = malloc(sizeof(int64_t) * na * na * (ni ? ni : 1));
  if (g_offsets == NULL) return -1;
  for (uint32_t seg = 0; seg < na; ++seg) {
    uint64_t off = (sizeof(segment_header) + 7u) & ~(uint64_t)7u;
    for (uint32_t owner = 0; owner < na; ++owner) {
      for (uint32_t i = 0; i < ni; ++i) {
        const int8_t m = g_table->agents[owner].membership[i];
        const int present = owner == seg ? m >= 0 : m == 1;
        if (!present) {
          *offset_at((int)seg, (int)owner, (int)i) = -1;
          continue;
        }
        *offset_at((int)seg, (int)owner, (int)i) = (int64_t)off;
        off += sizeof(slot_header) + ((g_table->items[i].size + 7u) & ~7u);
      }
    }
    g_sizes[seg] = off;
  }
  return 0;
}

static int process_alive(pid_t pid) { return pid > 0 && (kill(pid, 0) == 0 || errno == EPERM); }

static void init_segment(void* seg, int agent) {
  segment_header* h = (segment_header*)seg;
  h->version = RTDB_VERSION;
  h->config_hash = config_hash();
  h->agent = agent;
  h->creator_pid = (int32_t)getpid();
  h->created_ns = now_ns();
  h->total_size = g_sizes[agent];
  for (uint32_t owner = 0; owner < g_table->n_agents; ++owner) {
    for (uint32_t i = 0; i < g_table->n_items; ++i) {
      const int64_t off = *offset_at(agent, (int)owner, (int)i);
      if (off < 0) continue;
      slot_header* s = (slot_header*)(void*)((char*)seg + off) /* offsets are 8-aligned */;
      atomic_store(&s->seq, 0);
      s->size = g_table->items[i].size;
      s->stamp_ns = h->created_ns;
    }
  }
  atomic_store_explicit(&h->magic, RTDB_MAGIC, memory_order_release);
}

/* Attaches to a memory space's segment, creating it or reclaiming a stale one. */
static int attach(int space) {
  if (g_seg[space] != NULL) return 0;
  const int agent = agent_of(space);
  const char* set = set_name(space);
  const key_t key = set_key(space) + agent;
  const size_t size = (size_t)g_sizes[agent];
  for (int attempt = 0; attempt < 3; ++attempt) {
    int created = 1;
    int id = shmget(key, size, IPC_CREAT | IPC_EXCL | 0600);
    if (id < 0 && errno == EEXIST) {
      created = 0;
      id = shmget(key, 0, 0600);
      if (id < 0) {
        fprintf(stderr,
                "rtdb: the database of agent %d%s (key 0x%x) exists but is not ours: %s; set RTDB_KEY to another "
                "value\n",
                agent, set, (unsigned)key, strerror(errno));
        return -1;
      }
      struct shmid_ds ds;
      if (shmctl(id, IPC_STAT, &ds) < 0) return -1;
      /* Nobody attached and its creator gone: left by a crashed run. */
      const int stale = ds.shm_nattch == 0 && !process_alive(ds.shm_cpid);
      const int wrong_size = ds.shm_segsz != size;
      if (stale || (wrong_size && ds.shm_nattch == 0)) {
        if (verbose() || stale) {
          fprintf(stderr, "rtdb: reclaiming agent %d%s's database left by %s (pid %d)\n", agent, set,
                  stale ? "a crashed run" : "another configuration", (int)ds.shm_cpid);
        }
        shmctl(id, IPC_RMID, NULL);
        continue;
      }
      if (wrong_size) {
        fprintf(stderr,
                "rtdb: agent %d%s's database (key 0x%x) is in use by a program built with another RTDB configuration "
                "(%zu bytes, this one needs %zu); use the same configuration or set RTDB_KEY\n",
                agent, set, (unsigned)key, (size_t)ds.shm_segsz, size);
        return -1;
      }
    } else if (id < 0) {
      fprintf(stderr, "rtdb: cannot create agent %d%s's database (%zu bytes): %s\n", agent, set, size, strerror(errno));
      return -1;
    }
    void* seg = shmat(id, NULL, 0);
    if (seg == (void*)-1) {  // NOLINT(performance-no-int-to-ptr): shmat's error value
      fprintf(stderr, "rtdb: cannot attach agent %d%s's database: %s\n", agent, set, strerror(errno));
      return -1;
    }
    segment_header* h = (segment_header*)seg;
    if (created) {
      init_segment(seg, agent);
    } else {
      /* Wait (at most 1 s) for a creator that is still filling it in. */
      for (int i = 0; i < 1000 && atomic_load_explicit(&h->magic, memory_order_acquire) != RTDB_MAGIC; ++i) {
        usleep(1000);
      }
      if (atomic_load_explicit(&h->magic, memory_order_acquire) != RTDB_MAGIC || h->version != RTDB_VERSION ||
          h->config_hash != config_hash()) {
        fprintf(stderr,
                "rtdb: agent %d%s's database was made by a program with another RTDB configuration or version; "
                "rebuild both with the same configuration, or set RTDB_KEY\n",
                agent, set);
        shmdt(seg);
        return -1;
      }
    }
    g_seg[space] = seg;
    g_shmid[space] = id;
    if (verbose()) {
      fprintf(stderr, "rtdb: %s agent %d%s's database (%zu bytes)\n", created ? "created" : "attached", agent, set,
              size);
    }
    return 0;
  }
  fprintf(stderr, "rtdb: could not get agent %d%s's database after reclaiming it; try again\n", agent, set);
  return -1;
}

/* The frame semaphore's name of a memory space (its set's key base and agent). */
static void frame_sem_name(int space, char* name, size_t size) {
  snprintf(name, size, "/canhil-rtdb-%x-%d", (unsigned)set_key(space), agent_of(space));
}

static void detach(int space) {
  canhil_rtdb_frames_forget(space);
  if (g_seg[space] == NULL) return;
  shmdt(g_seg[space]);
  g_seg[space] = NULL;
  struct shmid_ds ds;
  if (shmctl(g_shmid[space], IPC_STAT, &ds) == 0 && ds.shm_nattch == 0) {
    shmctl(g_shmid[space], IPC_RMID, NULL); /* the last one out removes it */
    char name[64];
    frame_sem_name(space, name, sizeof name);
    sem_unlink(name);
  }
}

/* `owner` is an agent of the space's own set (SELF already replaced). */
static slot_header* slot(int space, int owner, int item) {
  if (!attached() || space < 0 || space >= spaces() || g_seg[space] == NULL) return NULL;
  if (owner < 0 || (uint32_t)owner >= g_table->n_agents || item < 0 || (uint32_t)item >= g_table->n_items) return NULL;
  const int64_t off = *offset_at(agent_of(space), owner, item);
  return off < 0 ? NULL : (slot_header*)(void*)((char*)g_seg[space] + off);
}

/* The whole value (size = s->size, offset 0) or a part of it; its age in ms. */
static int read_slot_range(const slot_header* s, size_t offset, size_t size, void* value) {
  const int64_t age = (now_ns() - read_slot_stamped(s, offset, size, value)) / 1000000;
  return age < 0 ? 0 : (age > INT_MAX ? INT_MAX : (int)age);
}

static int parse_agent(void) {
  const char* a = getenv("AGENT");
  if (a == NULL || *a == '\0') {
    fprintf(stderr, "rtdb: AGENT is not set; set it to this process's agent number:");
    for (uint32_t i = 0; i < g_table->n_agents; ++i) fprintf(stderr, " %u=%s", i, g_table->agents[i].name);
    fprintf(stderr, "\n");
    return -1;
  }
  char* end = NULL;
  const long n = strtol(a, &end, 10);
  if (*end != '\0' || n < 0 || n >= (long)g_table->n_agents) {
    fprintf(stderr, "rtdb: AGENT=%s is not an agent number; use 0 to %u\n", a, g_table->n_agents - 1);
    return -1;
  }
  return (int)n;
}

RTDB_EXPORT int DB_init(void) {
  if (g_me >= 0) {
    ++g_me_nesting;
    return 0;
  }
  if (table(1) == NULL) return -1;
  const int agent = parse_agent();
  if (agent < 0 || (!attached() && compute_layout() < 0)) return -1;
  const int me = agent + (canhil_second_set_from_environment() ? (int)g_table->n_agents : 0);
  if (attach(me) < 0) return -1;
  g_me = me;
  g_me_nesting = 1;
  return 0;
}

RTDB_EXPORT void DB_free(void) {
  if (g_me < 0 || --g_me_nesting > 0) return;
  if (g_all[set_of(g_me)] == 0) detach(g_me);
  g_me = -1;
}

RTDB_EXPORT int DB_init_all(int second_rtdb) {
  const int set = second_rtdb != 0;
  if (g_all[set] > 0) {
    ++g_all[set];
    return 0;
  }
  if (table(1) == NULL || (!attached() && compute_layout() < 0)) return -1;
  const int first = set * (int)g_table->n_agents;
  for (int a = 0; a < (int)g_table->n_agents; ++a) {
    if (attach(first + a) < 0) {
      for (int b = 0; b < a; ++b) {
        if (first + b != g_me) detach(first + b);
      }
      return -1;
    }
  }
  g_all[set] = 1;
  return 0;
}

RTDB_EXPORT void DB_free_all(int second_rtdb) {
  const int set = second_rtdb != 0;
  if (g_all[set] == 0 || --g_all[set] > 0) return;
  const int first = set * (int)g_table->n_agents;
  for (int a = 0; a < (int)g_table->n_agents; ++a) {
    if (first + a != g_me) detach(first + a);
  }
}

/* The agent number (AGENT), as CAMBADA's: the same in either set. */
RTDB_EXPORT int Whoami(void) { return g_me < 0 ? -1 : agent_of(g_me); }

RTDB_EXPORT int DB_space(void) { return g_me; }

/* The API's calls go through these (never through an exported symbol that
 * another library could interpose). `space` is a memory space; `owner` an
 * agent of its set, or SELF. */
static int put_in(int space, int to_agent, int id, const void* value, int life) {
  if (!attached() || space < 0) return -1;
  slot_header* s = slot(space, to_agent == SELF ? agent_of(space) : to_agent, id);
  if (s == NULL || value == NULL || life < 0) return -1;
  write_slot(s, value, now_ns() - (int64_t)life * 1000000);
  return (int)s->size;
}

static int read_slot(const slot_header* s, void* value) { return read_slot_range(s, 0, s->size, value); }

static int get_from(int space, int from_agent, int id, void* value) {
  if (!attached() || space < 0) return -1;
  const slot_header* s = slot(space, from_agent == SELF ? agent_of(space) : from_agent, id);
  if (s == NULL || value == NULL) return -1;
  return read_slot(s, value);
}

RTDB_EXPORT int DB_get_part(int agent, int from_agent, int id, size_t offset, size_t size, void* value) {
  if (!attached() || agent < 0) return -1;
  const slot_header* s = slot(agent, from_agent == SELF ? agent_of(agent) : from_agent, id);
  if (s == NULL || value == NULL || offset > s->size || size > s->size - offset) return -1;
  return read_slot_range(s, offset, size, value);
}

RTDB_EXPORT int DB_put_ranges(int agent, int to_agent, int id, const void* value, const size_t* ranges, int count,
                              int life) {
  if (!attached() || agent < 0 || count < 0 || life < 0 || value == NULL || (count > 0 && ranges == NULL)) return -1;
  slot_header* s = slot(agent, to_agent == SELF ? agent_of(agent) : to_agent, id);
  if (s == NULL) return -1;
  const size_t n = (size_t)count;
  for (size_t i = 0; i < n; ++i) {
    if (ranges[2 * i] > s->size || ranges[2 * i + 1] > s->size - ranges[2 * i]) return -1;
  }
  const uint32_t seq = take_slot(s);
  for (size_t i = 0; i < n; ++i) store_word_range(s, value, ranges[2 * i], ranges[2 * i + 1]);
  release_slot(s, seq, now_ns() - (int64_t)life * 1000000);
  return (int)s->size;
}

RTDB_EXPORT int DB_put(int id, void* value) { return g_me < 0 ? -1 : put_in(g_me, agent_of(g_me), id, value, 0); }

RTDB_EXPORT int DB_get(int from_agent, int id, void* value) { return get_from(g_me, from_agent, id, value); }

RTDB_EXPORT int DB_put_in(int agent, int to_agent, int id, void* value, int life) {
  return put_in(agent, to_agent, id, value, life);
}

RTDB_EXPORT int DB_get_from(int agent, int from_agent, int id, void* value) {
  return get_from(agent, from_agent, id, value);
}

RTDB_EXPORT void DB_set_config_file(const char* cf) {
  char* copy = cf != NULL ? strdup(cf) : NULL;
  if (cf != NULL && copy == NULL) return;
  free(g_config_file);
  g_config_file = copy;
  g_table_stale = 1;
  if (attached()) fprintf(stderr, "rtdb: DB_set_config_file after init: the item table changes once all is freed\n");
}

RTDB_EXPORT int DB_comm_put(int agent, int id, int size, void* value, int life) {
  (void)size; /* the table has it */
  if (g_me < 0) return -1;
  if (agent == SELF || agent == agent_of(g_me)) {
    fprintf(stderr, "rtdb: DB_comm_put: agent %d is this process's own; write its items with DB_put\n", agent_of(g_me));
    return -1;
  }
  if (agent < 0 || (uint32_t)agent >= g_table->n_agents || id < 0 || (uint32_t)id >= g_table->n_items ||
      g_table->agents[agent].membership[id] != 1) {
    fprintf(stderr, "rtdb: DB_comm_put: item %d is not a shared item of agent %d\n", id, agent);
    return -1;
  }
  return put_in(g_me, agent, id, value, life);
}

RTDB_EXPORT int DB_comm_ini(RTDBconf_var* rec) {
  if (g_me < 0 || rec == NULL) return -1;
  const int me = agent_of(g_me);
  int n = 0;
  for (uint32_t id = 0; id < g_table->n_items; ++id) n += g_table->agents[me].membership[id] == 1;
  if (n > MAX_RECS) {
    fprintf(stderr, "rtdb: DB_comm_ini: agent %d has %d shared items, more than MAX_RECS (%d)\n", me, n, MAX_RECS);
    return -1;
  }
  n = 0;
  for (uint32_t id = 0; id < g_table->n_items; ++id) {
    if (g_table->agents[me].membership[id] != 1) continue;
    rec[n++] = (RTDBconf_var){(int)id, (int)g_table->items[id].size, (int)g_table->items[id].period};
  }
  return n;
}

RTDB_EXPORT int DB_agent_count(void) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL ? (int)t->n_agents : 0;
}

RTDB_EXPORT int DB_item_count(void) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL ? (int)t->n_items : 0;
}

RTDB_EXPORT const char* DB_agent_name(int agent) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL && agent >= 0 && (uint32_t)agent < t->n_agents ? t->agents[agent].name : NULL;
}

RTDB_EXPORT const char* DB_item_name(int id) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL && id >= 0 && (uint32_t)id < t->n_items ? t->items[id].name : NULL;
}

RTDB_EXPORT int DB_item_size(int id) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL && id >= 0 && (uint32_t)id < t->n_items && t->items[id].size > 0 ? (int)t->items[id].size : -1;
}

RTDB_EXPORT int DB_item_shared(int agent, int id) {
  const canhil_rtdb_table* t = table(0);
  if (t == NULL || agent < 0 || (uint32_t)agent >= t->n_agents || id < 0 || (uint32_t)id >= t->n_items) return -1;
  return t->agents[agent].membership[id];
}

RTDB_EXPORT const char* DB_config_source(void) {
  const canhil_rtdb_table* t = table(0);
  return t != NULL ? t->source : NULL;
}

RTDB_EXPORT int DB_signal_frame(int space) {
  const canhil_rtdb_table* t = table(0);
  if (t == NULL || space < 0 || space >= SETS * (int)t->n_agents) return -1;
  return canhil_rtdb_frames_post(space, frame_sem_name, g_seg[space] != NULL);
}

RTDB_EXPORT int DB_wait_frame(int timeout_ms) {
  if (g_me < 0) return -1;
  return canhil_rtdb_frames_wait(g_me, frame_sem_name, timeout_ms);
}
