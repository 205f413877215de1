/* rtdb_api.h — the RTDB calls of one agent's processes (the agent, the vision,
 * the low-level handler), with CAMBADA's names and signatures. canhil's own
 * header; the library is canhil's (docs/rtdb.md).
 *
 * Each agent has its own database: its own items (the shared and local items
 * of its schema) and a copy of every other agent's shared items. The process's
 * agent is the number in the AGENT environment variable. Ages are in ms.
 * All calls are thread-safe after DB_init. */
#ifndef CANHIL_RTDB_API_H
#define CANHIL_RTDB_API_H

#include "rtdbdefs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Attaches this process to its agent's database (AGENT), creating it when it
 * does not exist yet and reclaiming one a crashed run left. Returns 0, or -1
 * with a message on stderr saying what to do. Calls nest: each successful
 * DB_init needs its DB_free. */
int DB_init(void);

/* Detaches (after the last nested DB_init); the last process to detach from a
 * database removes it. */
void DB_free(void);

/* Writes item `id` of this agent, stamped now. Returns the item's size in
 * bytes, or -1 (not initialised, an id this agent's schema does not have,
 * value NULL). */
int DB_put(int id, void* value);

/* Reads item `id` of agent `from_agent` into `value`: this agent's own item
 * when from_agent is Whoami() or SELF, else this database's copy of that
 * agent's shared item. Returns the item's age in ms, or -1 (not initialised,
 * no such item here). An item never written reads as zeros, aged from the
 * database's creation (CAMBADA's library returns INT_MIN there). */
int DB_get(int from_agent, int id, void* value);

/* This process's agent number, or -1 before DB_init. */
int Whoami(void);

/* Writes into agent `agent`'s database the item `id` of agent `to_agent`
 * (`agent` itself or SELF: its own item; another agent: the copy of that
 * agent's shared item), as if written `life` ms ago (life >= 0). Needs that
 * database attached (DB_init for this agent, DB_init_all for any). Returns
 * the item's size in bytes, or -1. */
int DB_put_in(int agent, int to_agent, int id, void* value, int life);

#ifdef __cplusplus
}
#endif

#endif
