/* The item table read at run time: a team's rtdb.ini (CAMBADA's format) and,
 * optionally, the rtdb_user.h that names its items. See rtdb_table.h.
 *
 * rtdb.ini, line by line (blank lines and "##" comments skipped):
 *   # N NAME              starts agent N's section; N counts 0, 1, 2, ...
 *   ID SIZE PERIOD s|l    one of that agent's items: shared or local
 * rtdb_user.h: "#define NAME NUMBER" for every agent and item, N_AGENTS,
 * N_ITEMS, include guards and comments. */
#define _GNU_SOURCE  // NOLINT(bugprone-reserved-identifier): getline, strdup
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtdb_internal.h"
#include "rtdbdefs.h"

#define WS " \t\r\n\v\f"
#define MAX_ITEM_SIZE (64u << 20) /* a sanity bound: 64 MiB */

static const char kIniFormat[] =
    "an rtdb.ini has \"# N NAME\" lines, each starting agent N's section, followed by \"ID SIZE PERIOD s|l\" lines";
static const char kMismatch[] =
    "the two files come from different configurations: use the rtdb_user.h and rtdb.ini of one run of the generator";

typedef struct {
  char* name;
  int named; /* the ini gave a name */
  int line;
  int8_t kind[MAX_RECS]; /* 1 shared, 0 local, -1 none */
  int item_line[MAX_RECS];
} ini_agent;

typedef struct {
  char* name;
  long value;
  int line;
} user_define;

typedef struct {
  char* error;
  size_t error_size;
  int n_agents;
  ini_agent agents[CANHIL_RTDB_MAX_AGENTS];
  uint32_t size[MAX_RECS]; /* 0: no agent has it */
  uint32_t period[MAX_RECS];
  int size_line[MAX_RECS];
  const char* names[MAX_RECS]; /* from rtdb_user.h */
  int max_id;
} parse_state;

__attribute__((format(printf, 4, 5))) static int fail(parse_state* p, const char* file, int line, const char* fmt,
                                                      ...) {
  char message[768];
  va_list args;
  va_start(args, fmt);
  /* clang-analyzer 14 calls args uninitialised here (only through the build's compile database): a false positive. */
  vsnprintf(message, sizeof message, fmt, args);  // NOLINT(clang-analyzer-valist.Uninitialized)
  va_end(args);
  if (line > 0) {
    snprintf(p->error, p->error_size, "%s:%d: %s", file, line, message);
  } else {
    snprintf(p->error, p->error_size, "%s: %s", file, message);
  }
  return -1;
}

static int parse_long(const char* s, int base, long* out) {
  if (s == NULL || *s == '\0') return 0;
  char* end = NULL;
  errno = 0;
  const long v = strtol(s, &end, base);
  if (errno != 0 || *end != '\0') return 0;
  *out = v;
  return 1;
}

static int agent_section(parse_state* p, const char* file, int line, char* first, char** save) {
  /* "# N NAME" or "#N NAME" (CAMBADA reads the number right after the '#'). */
  const char* number = first[1] != '\0' ? first + 1 : strtok_r(NULL, WS, save);
  long n = 0;
  if (!parse_long(number, 10, &n)) {
    return fail(p, file, line, "expected an agent section \"# NUMBER NAME\"; %s", kIniFormat);
  }
  if (n != p->n_agents) {
    return fail(p, file, line,
                "this is agent %ld's section, but agent %d's comes next: number the sections 0, 1, 2, ...", n,
                p->n_agents);
  }
  if (p->n_agents == CANHIL_RTDB_MAX_AGENTS) {
    return fail(p, file, line, "more than %d agents; canhil's RTDB serves at most %d", CANHIL_RTDB_MAX_AGENTS,
                CANHIL_RTDB_MAX_AGENTS);
  }
  const char* name = strtok_r(NULL, WS, save);
  const char* extra = name != NULL ? strtok_r(NULL, WS, save) : NULL;
  if (extra != NULL) return fail(p, file, line, "unexpected \"%s\" after agent %ld's name", extra, n);
  ini_agent* a = &p->agents[p->n_agents];
  char fallback[32];
  snprintf(fallback, sizeof fallback, "agent%ld", n);
  a->name = strdup(name != NULL ? name : fallback);
  a->named = name != NULL;
  a->line = line;
  memset(a->kind, -1, sizeof a->kind);
  ++p->n_agents;
  return a->name != NULL ? 0 : fail(p, file, line, "out of memory");
}

static int item_line(parse_state* p, const char* file, int line, char* first, char** save) {
  if (p->n_agents == 0) {
    return fail(p, file, line, "an item before the first agent section (\"# 0 NAME\"); %s", kIniFormat);
  }
  const char* words[5] = {first, NULL, NULL, NULL, NULL};
  for (int i = 1; i < 5; ++i) words[i] = strtok_r(NULL, WS, save);
  long id = 0;
  long size = 0;
  long period = 0;
  if (!parse_long(words[0], 10, &id) || !parse_long(words[1], 10, &size) || !parse_long(words[2], 10, &period) ||
      words[3] == NULL || words[4] != NULL) {
    return fail(p, file, line, "expected an item line \"ID SIZE PERIOD s|l\"; %s", kIniFormat);
  }
  if (strcmp(words[3], "s") != 0 && strcmp(words[3], "l") != 0) {
    return fail(p, file, line, "item %ld is \"%s\"; write s (shared) or l (local)", id, words[3]);
  }
  if (id < 0 || id >= MAX_RECS)
    return fail(p, file, line, "item id %ld is out of range: ids are 0 to %d", id, MAX_RECS - 1);
  if (size <= 0 || size > (long)MAX_ITEM_SIZE) {
    return fail(p, file, line, "item %ld has size %ld; give its size in bytes (1 to %u)", id, size, MAX_ITEM_SIZE);
  }
  if (period < 0) return fail(p, file, line, "item %ld has period %ld; give 0 or more", id, period);
  ini_agent* a = &p->agents[p->n_agents - 1];
  if (a->kind[id] >= 0) {
    return fail(p, file, line, "item %ld is listed twice in agent %s's section (first on line %d)", id, a->name,
                a->item_line[id]);
  }
  if (p->size[id] != 0 && p->size[id] != (uint32_t)size) {
    return fail(p, file, line, "item %ld is %ld bytes here but %u bytes on line %d; an item has one size", id, size,
                p->size[id], p->size_line[id]);
  }
  a->kind[id] = strcmp(words[3], "s") == 0 ? 1 : 0;
  a->item_line[id] = line;
  if (p->size[id] == 0) {
    p->size[id] = (uint32_t)size;
    p->period[id] = (uint32_t)period;
    p->size_line[id] = line;
  }
  if (id > p->max_id) p->max_id = (int)id;
  return 0;
}

static int parse_ini(parse_state* p, const char* file) {
  FILE* f = fopen(file, "r");
  if (f == NULL) return fail(p, file, 0, "cannot read the item table (%s)", strerror(errno));
  char* text = NULL;
  size_t cap = 0;
  int line = 0;
  int rc = 0;
  while (rc == 0 && getline(&text, &cap, f) >= 0) {
    ++line;
    char* save = NULL;
    char* first = strtok_r(text, WS, &save);
    if (first == NULL || (first[0] == '#' && first[1] == '#')) continue;
    rc = first[0] == '#' ? agent_section(p, file, line, first, &save) : item_line(p, file, line, first, &save);
  }
  free(text);
  fclose(f);
  if (rc == 0 && p->n_agents == 0) rc = fail(p, file, 0, "no agent section (\"# 0 NAME\"); %s", kIniFormat);
  return rc;
}

/* Removes comments (which may span lines: *in_comment carries the state). */
static void strip_comments(char* s, int* in_comment) {
  char* out = s;
  for (const char* c = s; *c != '\0';) {
    if (*in_comment) {
      if (c[0] == '*' && c[1] == '/') {
        *in_comment = 0;
        c += 2;
      } else {
        ++c;
      }
    } else if (c[0] == '/' && c[1] == '*') {
      *in_comment = 1;
      *out++ = ' ';
      c += 2;
    } else if (c[0] == '/' && c[1] == '/') {
      break;
    } else {
      *out++ = *c++;
    }
  }
  *out = '\0';
}

static int parse_user_h(parse_state* p, const char* file, user_define** defs, int* n_defs) {
  FILE* f = fopen(file, "r");
  if (f == NULL) return fail(p, file, 0, "cannot read the item names (%s)", strerror(errno));
  char* text = NULL;
  size_t cap = 0;
  int line = 0;
  int rc = 0;
  int in_comment = 0;
  int capacity = 0;
  while (rc == 0 && getline(&text, &cap, f) >= 0) {
    ++line;
    strip_comments(text, &in_comment);
    char* save = NULL;
    char* word = strtok_r(text, WS, &save);
    if (word == NULL) continue;
    if (word[0] != '#') {
      rc = fail(p, file, line, "not a line of a generated rtdb_user.h (#define NAME NUMBER)");
      break;
    }
    const char* directive = word[1] != '\0' ? word + 1 : strtok_r(NULL, WS, &save);
    if (directive == NULL || strcmp(directive, "define") != 0) {
      static const char* const kIgnored[] = {"ifndef", "ifdef", "endif", "if", "else", "elif", "pragma", "include"};
      int known = 0;
      for (size_t i = 0; directive != NULL && i < sizeof kIgnored / sizeof kIgnored[0]; ++i) {
        known |= strcmp(directive, kIgnored[i]) == 0;
      }
      if (!known) rc = fail(p, file, line, "not a line of a generated rtdb_user.h (#define NAME NUMBER)");
      continue;
    }
    const char* name = strtok_r(NULL, WS, &save);
    char* value = strtok_r(NULL, WS, &save);
    const char* extra = value != NULL ? strtok_r(NULL, WS, &save) : NULL;
    if (name == NULL) {
      rc = fail(p, file, line, "#define without a name");
      break;
    }
    if (value == NULL) continue; /* an include guard */
    const size_t len = strlen(value);
    if (len > 2 && value[0] == '(' && value[len - 1] == ')') {
      value[len - 1] = '\0';
      ++value;
    }
    long v = 0;
    if (extra != NULL || !parse_long(value, 0, &v)) {
      rc = fail(p, file, line, "%s's value is not a whole number; rtdb_user.h has \"#define NAME NUMBER\" lines", name);
      break;
    }
    for (int i = 0; i < *n_defs; ++i) {
      if (strcmp((*defs)[i].name, name) == 0) {
        rc = fail(p, file, line, "%s is defined twice (first on line %d)", name, (*defs)[i].line);
      }
    }
    if (rc != 0) break;
    if (*n_defs == capacity) {
      capacity = capacity ? 2 * capacity : 64;
      user_define* grown = realloc(*defs, sizeof **defs * (size_t)capacity);
      if (grown == NULL) {
        rc = fail(p, file, line, "out of memory");
        break;
      }
      *defs = grown;
    }
    (*defs)[*n_defs] = (user_define){strdup(name), v, line};
    ++*n_defs;
  }
  free(text);
  fclose(f);
  return rc;
}

/* Agent defines must number the ini's agents as the ini does; the other
 * defines (but N_AGENTS, N_ITEMS) name items; every ini item needs a name. */
static int reconcile(parse_state* p, const char* ini, const char* user_h, const user_define* defs, int n_defs) {
  int agent_named[CANHIL_RTDB_MAX_AGENTS] = {0};
  int n_items = 0;
  for (int i = 0; i < n_defs; ++i) {
    const user_define* d = &defs[i];
    if (strcmp(d->name, "N_AGENTS") == 0) {
      if (d->value != p->n_agents) {
        return fail(p, user_h, d->line, "N_AGENTS is %ld but %s has %d agent sections; %s", d->value, ini, p->n_agents,
                    kMismatch);
      }
      continue;
    }
    if (strcmp(d->name, "N_ITEMS") == 0) continue; /* checked below */
    int agent = -1;
    for (int a = 0; a < p->n_agents; ++a) {
      if (strcmp(p->agents[a].name, d->name) == 0) agent = a;
    }
    if (agent >= 0) {
      if (d->value != agent) {
        return fail(p, user_h, d->line, "%s is agent %ld here but agent %d in %s:%d; %s", d->name, d->value, agent, ini,
                    p->agents[agent].line, kMismatch);
      }
      agent_named[agent] = 1;
      continue;
    }
    if (d->value < 0 || d->value >= MAX_RECS) {
      return fail(p, user_h, d->line, "item %s has id %ld, out of range: ids are 0 to %d", d->name, d->value,
                  MAX_RECS - 1);
    }
    const char** slot = &p->names[d->value];
    if (*slot != NULL) return fail(p, user_h, d->line, "%s and %s both have id %ld", *slot, d->name, d->value);
    *slot = d->name;
    ++n_items;
    if (d->value > p->max_id) p->max_id = (int)d->value;
  }
  for (int i = 0; i < n_defs; ++i) {
    if (strcmp(defs[i].name, "N_ITEMS") == 0 && defs[i].value != n_items) {
      return fail(p, user_h, defs[i].line, "N_ITEMS is %ld but the header names %d items", defs[i].value, n_items);
    }
  }
  for (int a = 0; a < p->n_agents; ++a) {
    if (p->agents[a].named && !agent_named[a]) {
      return fail(p, ini, p->agents[a].line, "agent %s is not in %s; %s", p->agents[a].name, user_h, kMismatch);
    }
  }
  for (int id = 0; id < MAX_RECS; ++id) {
    if (p->size[id] != 0 && p->names[id] == NULL) {
      return fail(p, ini, p->size_line[id], "item %d has no name in %s; %s", id, user_h, kMismatch);
    }
  }
  return 0;
}

static canhil_rtdb_table* build(const parse_state* p, const char* source) {
  const uint32_t n_items = (uint32_t)(p->max_id + 1);
  canhil_rtdb_table* t = calloc(1, sizeof *t);
  canhil_rtdb_item* items = calloc(n_items ? n_items : 1, sizeof *items);
  canhil_rtdb_agent* agents = calloc((size_t)p->n_agents, sizeof *agents);
  if (t != NULL) {
    t->n_agents = (uint32_t)p->n_agents;
    t->n_items = n_items;
    t->items = items;
    t->agents = agents;
    t->source = strdup(source);
  }
  if (t == NULL) {
    free(items);
    free(agents);
    return NULL;
  }
  if (items == NULL || agents == NULL || t->source == NULL) {
    canhil_rtdb_table_free(t);
    return NULL;
  }
  int ok = 1;
  for (uint32_t id = 0; id < n_items; ++id) {
    char fallback[32];
    snprintf(fallback, sizeof fallback, "item%u", id);
    items[id].name = strdup(p->names[id] != NULL ? p->names[id] : fallback);
    items[id].size = p->size[id];
    items[id].period = p->period[id];
    ok &= items[id].name != NULL;
  }
  for (int a = 0; a < p->n_agents; ++a) {
    int8_t* membership = malloc(n_items ? n_items : 1);
    if (membership != NULL) memcpy(membership, p->agents[a].kind, n_items);
    agents[a].membership = membership;
    agents[a].name = strdup(p->agents[a].name);
    ok &= membership != NULL && agents[a].name != NULL;
  }
  if (!ok) {
    canhil_rtdb_table_free(t);
    return NULL;
  }
  return t;
}

canhil_rtdb_table* canhil_rtdb_table_load(const char* ini, const char* user_h, char* error, size_t error_size) {
  parse_state* p = calloc(1, sizeof *p);
  if (p == NULL) {
    snprintf(error, error_size, "%s: out of memory", ini);
    return NULL;
  }
  p->error = error;
  p->error_size = error_size;
  p->max_id = -1;
  user_define* defs = NULL;
  int n_defs = 0;
  int rc = parse_ini(p, ini);
  if (rc == 0 && user_h != NULL) rc = parse_user_h(p, user_h, &defs, &n_defs);
  if (rc == 0 && user_h != NULL) rc = reconcile(p, ini, user_h, defs, n_defs);
  canhil_rtdb_table* t = NULL;
  if (rc == 0) {
    char source[1024];
    if (user_h != NULL) {
      snprintf(source, sizeof source, "%s (names from %s)", ini, user_h);
    } else {
      snprintf(source, sizeof source, "%s", ini);
    }
    t = build(p, source);
    if (t == NULL) snprintf(error, error_size, "%s: out of memory", ini);
  }
  for (int i = 0; i < n_defs; ++i) free(defs[i].name);
  free(defs);
  for (int a = 0; a < p->n_agents; ++a) free(p->agents[a].name);
  free(p);
  return t;
}

void canhil_rtdb_table_free(canhil_rtdb_table* t) {
  if (t == NULL) return;
  for (uint32_t id = 0; t->items != NULL && id < t->n_items; ++id) free((void*)t->items[id].name);
  for (uint32_t a = 0; t->agents != NULL && a < t->n_agents; ++a) {
    free((void*)t->agents[a].name);
    free((void*)t->agents[a].membership);
  }
  free((void*)t->items);
  free((void*)t->agents);
  free((void*)t->source);
  free(t);
}
