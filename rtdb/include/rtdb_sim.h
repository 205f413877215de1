/* rtdb_sim.h — the RTDB calls of a process that serves several agents at once
 * (a simulator, canhil's emulator, the replicator), with CAMBADA's names and
 * signatures. canhil's own header (docs/rtdb.md). */
#ifndef CANHIL_RTDB_SIM_H
#define CANHIL_RTDB_SIM_H

#include "rtdbdefs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Attaches to every agent's database, creating them as needed. `second_rtdb`
 * is accepted and ignored (CAMBADA's second team never worked). Returns 0, or
 * -1 with a message on stderr (nothing stays attached then). Calls nest: each
 * successful DB_init_all needs its DB_free_all. */
int DB_init_all(int second_rtdb);

/* Detaches from every agent's database (after the last nested DB_init_all). */
void DB_free_all(int second_rtdb);

/* As in rtdb_api.h: writes item `id` of agent `to_agent` into agent `agent`'s
 * database, aged `life` ms. Returns the item's size, or -1. */
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
