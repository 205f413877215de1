/* rtdb_sim.h — the RTDB calls of a process that serves several agents at once
 * (a simulator, canhil's emulator, the replicator), with CAMBADA's names and
 * signatures. canhil's own header (docs/rtdb.md). */
#ifndef CANHIL_RTDB_SIM_H
#define CANHIL_RTDB_SIM_H

#include "rtdbdefs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Attaches to every agent's database, creating them as needed: the first
 * set's (memory spaces 0..N-1, N the table's agents) or, with `second_rtdb`
 * non-zero, the second team's (spaces N..2N-1, as CAMBADA's simulator
 * numbers them). The second set's keys are the first's plus 64: its agents
 * run with SECOND_RTDB=1, or with RTDB_KEY set 64 higher. Returns 0, or -1
 * with a message on stderr (nothing of that set stays attached then). Calls
 * nest per set: each successful DB_init_all needs its DB_free_all. */
int DB_init_all(int second_rtdb);

/* Detaches from that set's databases (after its last nested DB_init_all). */
void DB_free_all(int second_rtdb);

/* As in rtdb_api.h: writes item `id` of agent `to_agent` into memory space
 * `agent`'s database (N + a for agent a of the second set; `to_agent` is an
 * agent of the same set), aged `life` ms. Returns the item's size, or -1. */
int DB_put_in(int agent, int to_agent, int id, void* value, int life);

/* Reads, from agent `agent`'s database, item `id` of agent `from_agent`
 * (SELF: `agent` itself). Returns the age in ms, or -1. */
int DB_get_from(int agent, int from_agent, int id, void* value);

/* Where the next DB_init / DB_init_all reads the item table: an rtdb.ini
 * (CAMBADA's format: "# N NAME" starts agent N's section, "ID SIZE PERIOD s|l"
 * lines follow). NULL restores the default: the table linked into the
 * program (canhil::rtdb, or your generated rtdb_config.c), or, in librtdb.so,
 * $CANHIL_RTDB_INI or CONFIG_FILE. Call it before init; after init it takes
 * effect once everything is freed. */
void DB_set_config_file(const char* cf);

#ifdef __cplusplus
}
#endif

#endif
