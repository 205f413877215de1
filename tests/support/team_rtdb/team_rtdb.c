/* tests/support/team_rtdb/team_rtdb.c — a team's RTDB library, for the tests
 * that load one (open_library): CAMBADA's C API for one agent and for every
 * agent, written here from scratch, with keys of its own, so that a test can
 * tell that writes went through IT:
 *  - one System V segment per memory space: key TEAM_RTDB_KEY (default
 *    0x7E5A0000) + space, mode 0600, removed by the last process out;
 *  - the item table from an rtdb.ini (DB_set_config_file, else
 *    ../config/rtdb.ini): "# N NAME" sections of "ID SIZE PERIOD s|l" lines;
 *  - every put counted, per space and item, in the segment:
 *    standin_put_count(space, id), from any process;
 *  - ages in ms (CLOCK_MONOTONIC); an item never written answers INT_MIN, as
 *    CAMBADA's library does; put returns the size, as CAMBADA's does.
 * No locking: one writer per item, as CAMBADA's. Built a second time with
 * TEAM_RTDB_WITHOUT_GET_FROM: a library that lacks DB_get_from. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): strdup
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <time.h>

#include "rtdb_api.h"
#include "rtdb_sim.h"

#define API __attribute__((visibility("default")))
#define SPACES 8
#define ITEMS 100
#define MAGIC 0x5445414Du /* "TEAM" */

typedef struct {
  int n_agents;
  uint32_t size[ITEMS];
  int8_t kind[SPACES][ITEMS]; /* 1 shared, 0 local, -1 none */
} table;

typedef struct {
  uint32_t magic;
  uint32_t puts[ITEMS];
} segment_header;

typedef struct {
  int64_t stamp_ms;
  int32_t written;
  int32_t pad;
} record; /* the data follows, padded to 8 bytes */

static table g_table;
static int g_loaded = 0;
static char* g_config = NULL;
static void* g_seg[SPACES];
static int g_shmid[SPACES];
static int g_me = -1;
static int g_all = 0;

static key_t base_key(void) {
  const char* k = getenv("TEAM_RTDB_KEY");
  return k != NULL && *k != '\0' ? (key_t)strtol(k, NULL, 0) : (key_t)0x7E5A0000;
}

static int64_t now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

static int load(void) {
  if (g_loaded) return 0;
  const char* path = g_config != NULL ? g_config : "../config/rtdb.ini";
  FILE* f = fopen(path, "r");
  if (f == NULL) {
    fprintf(stderr, "team_rtdb: cannot read %s\n", path);
    return -1;
  }
  memset(&g_table, 0, sizeof g_table);
  memset(g_table.kind, -1, sizeof g_table.kind);
  char line[256];
  int agent = -1;
  while (fgets(line, sizeof line, f) != NULL) {
    int id = 0;
    int size = 0;
    int period = 0;
    char kind = 0;
    if (line[0] == '#' && line[1] == '#') continue;
    if (line[0] == '#') {
      if (sscanf(line + 1, "%d", &agent) != 1 || agent != g_table.n_agents || agent >= SPACES) break;
      ++g_table.n_agents;
    } else if (sscanf(line, "%d %d %d %c", &id, &size, &period, &kind) == 4) {
      if (agent < 0 || id < 0 || id >= ITEMS || size <= 0) break;
      g_table.size[id] = (uint32_t)size;
      g_table.kind[agent][id] = kind == 's' ? 1 : 0;
    }
  }
  const int complete = feof(f);
  fclose(f);
  if (!complete || g_table.n_agents == 0) {
    fprintf(stderr, "team_rtdb: %s is not an rtdb.ini I can read\n", path);
    return -1;
  }
  g_loaded = 1;
  return 0;
}

static int present(int space, int owner, int id) {
  const int8_t k = g_table.kind[owner][id];
  return owner == space ? k >= 0 : k == 1;
}

/* The byte offset of (owner, id) in space's segment, or -1; with owner -1,
 * the segment's size. */
static int64_t offset(int space, int owner, int id) {
  int64_t off = (sizeof(segment_header) + 7) & ~(size_t)7; /* records are 8-aligned */
  for (int a = 0; a < g_table.n_agents; ++a) {
    for (int i = 0; i < ITEMS; ++i) {
      if (!present(space, a, i)) continue;
      if (a == owner && i == id) return off;
      off += (int64_t)sizeof(record) + ((g_table.size[i] + 7) & ~7u);
    }
  }
  return owner < 0 ? off : -1;
}

static int attach(int space) {
  if (g_seg[space] != NULL) return 0;
  const int id = shmget(base_key() + space, (size_t)offset(space, -1, 0), IPC_CREAT | 0600);
  void* seg = id < 0 ? (void*)-1 : shmat(id, NULL, 0);  // NOLINT(performance-no-int-to-ptr)
  if (seg == (void*)-1) {                               // NOLINT(performance-no-int-to-ptr)
    fprintf(stderr, "team_rtdb: cannot attach space %d\n", space);
    return -1;
  }
  ((segment_header*)seg)->magic = MAGIC; /* a new segment is all zeros */
  g_seg[space] = seg;
  g_shmid[space] = id;
  return 0;
}

static void detach(int space) {
  if (g_seg[space] == NULL) return;
  shmdt(g_seg[space]);
  g_seg[space] = NULL;
  struct shmid_ds ds;
  if (shmctl(g_shmid[space], IPC_STAT, &ds) == 0 && ds.shm_nattch == 0) shmctl(g_shmid[space], IPC_RMID, NULL);
}

static record* find(int space, int owner, int id) {
  if (space < 0 || space >= g_table.n_agents || g_seg[space] == NULL) return NULL;
  if (owner == SELF) owner = space;
  if (owner < 0 || owner >= g_table.n_agents || id < 0 || id >= ITEMS) return NULL;
  const int64_t off = offset(space, owner, id);
  return off < 0 ? NULL : (record*)(void*)((char*)g_seg[space] + off);
}

static int put_in(int space, int owner, int id, const void* value, int life) {
  record* r = find(space, owner, id);
  if (r == NULL || value == NULL) return -1;
  memcpy(r + 1, value, g_table.size[id]);
  __atomic_store_n(&r->stamp_ms, now_ms() - life, __ATOMIC_RELEASE);
  r->written = 1;
  __atomic_fetch_add(&((segment_header*)g_seg[space])->puts[id], 1u, __ATOMIC_RELAXED);
  return (int)g_table.size[id];
}

static int get_from(int space, int owner, int id, void* value) {
  const record* r = find(space, owner, id);
  if (r == NULL || value == NULL) return -1;
  memcpy(value, r + 1, g_table.size[id]);
  if (!r->written) return INT_MIN;
  /* The stamp before the clock: read after it, a write that lands in between
   * (the next frame) would make the age negative. */
  const int64_t stamp = __atomic_load_n(&r->stamp_ms, __ATOMIC_ACQUIRE);
  return (int)(now_ms() - stamp);
}

__attribute__((destructor)) static void release(void) { free(g_config); } /* at dlclose */

API void DB_set_config_file(const char* cf) {
  free(g_config);
  g_config = cf != NULL ? strdup(cf) : NULL;
  g_loaded = 0;
}

API int DB_init_all(int second_rtdb) {
  (void)second_rtdb;
  if (load() < 0) return -1;
  for (int s = 0; s < g_table.n_agents; ++s) {
    if (attach(s) < 0) return -1;
  }
  g_all = 1;
  return 0;
}

API void DB_free_all(int second_rtdb) {
  (void)second_rtdb;
  for (int s = 0; s < g_table.n_agents; ++s) {
    if (s != g_me) detach(s);
  }
  g_all = 0;
}

API int DB_init(void) {
  const char* a = getenv("AGENT");
  if (a == NULL || load() < 0) return -1;
  const int me = atoi(a);
  if (me < 0 || me >= g_table.n_agents || attach(me) < 0) return -1;
  g_me = me;
  return 0;
}

API void DB_free(void) {
  if (g_me >= 0 && !g_all) detach(g_me);
  g_me = -1;
}

API int Whoami(void) { return g_me; }
API int DB_put(int id, void* value) { return put_in(g_me, g_me, id, value, 0); }
API int DB_get(int from_agent, int id, void* value) { return get_from(g_me, from_agent, id, value); }
API int DB_put_in(int space, int owner, int id, void* value, int life) { return put_in(space, owner, id, value, life); }
#ifndef TEAM_RTDB_WITHOUT_GET_FROM
API int DB_get_from(int space, int owner, int id, void* value) { return get_from(space, owner, id, value); }
#endif

/* Puts of item `id` into space `space` so far (from any process), or -1 when
 * that space's segment does not exist. */
API int standin_put_count(int space, int id) {
  const int shmid = shmget(base_key() + space, 0, 0);
  void* seg = shmid < 0 ? (void*)-1 : shmat(shmid, NULL, SHM_RDONLY);  // NOLINT(performance-no-int-to-ptr)
  if (seg == (void*)-1 || id < 0 || id >= ITEMS) return -1;            // NOLINT(performance-no-int-to-ptr)
  const int n = (int)__atomic_load_n(&((const segment_header*)seg)->puts[id], __ATOMIC_RELAXED);
  shmdt(seg);
  return n;
}
