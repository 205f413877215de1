/* rtdb_comm.h — the RTDB calls of a team-communication process (CAMBADA's comm
 * daemon): what to send and where received items go. CAMBADA's names and
 * signatures; canhil's own header (docs/rtdb.md). */
#ifndef CANHIL_RTDB_COMM_H
#define CANHIL_RTDB_COMM_H

#include "rtdb_api.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Stores item `id` received from agent `agent` in this agent's database (its
 * copy of that agent's shared item), aged `life` ms. `size` is ignored (the
 * table gives it). Refuses (-1, with a message) to write into this agent's
 * own items (agent == Whoami() or SELF) and an item that is not `agent`'s
 * shared item. Returns the item's size, or -1. Needs DB_init. */
int DB_comm_put(int agent, int id, int size, void* value, int life);

/* Fills rec[0..n-1] with this agent's shared items (id, size, period), in id
 * order, and returns n (at most MAX_RECS; size rec accordingly), or -1 before
 * DB_init. */
int DB_comm_ini(RTDBconf_var* rec);

#ifdef __cplusplus
}
#endif

#endif
