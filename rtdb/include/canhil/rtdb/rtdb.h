/* canhil/rtdb/rtdb.h — the real-time database (RTDB): a shared-memory
 * blackboard per robot, with the C API the CAMBADA laptop software calls and
 * canhil's extensions.
 *
 * Each agent (robot or base station, numbered by their order in the
 * configuration; the process's agent comes from the AGENT environment
 * variable) has its own System V shared-memory segment, readable and writable
 * by its owner only. It holds the agent's own items (the shared and local
 * items of its schema) and a copy of every other agent's shared items, which
 * the replicator (canhil rtdb replicate) keeps up to date.
 *
 * Every item carries the time it was written; readers get it as an age. A
 * write is never seen half done: items are sequence-locked. All functions are
 * thread-safe after DB_init / DB_init_all (DB_set_config_file and the first
 * call of any function belong to set-up, on one thread).
 *
 * The CAMBADA calls are declared in CAMBADA's headers, which this one
 * includes: rtdb_api.h (one agent), rtdb_sim.h (every agent, the item table's
 * file), rtdb_comm.h (team communication), rtdbdefs.h (SELF, MAX_RECS,
 * RTDBconf_var). A CAMBADA program includes "rtdb.h" (rtdb_user.h and
 * rtdb_api.h) instead of this header.
 *
 * The item table (which items exist, their sizes, who has which):
 *  - canhil::rtdb and canhil::rtdb_core + your generated rtdb_config.c: the
 *    table canhil-rtdb-gen compiled from an AGENTS / ITEM / SCHEMA /
 *    ASSIGNMENT file (docs/rtdb.md), unless DB_set_config_file names an
 *    rtdb.ini;
 *  - librtdb.so (canhil::rtdb_shared): an rtdb.ini read at DB_init /
 *    DB_init_all, as CAMBADA's library does: DB_set_config_file's, else
 *    $CANHIL_RTDB_INI, else CONFIG_FILE (../config/rtdb.ini).
 * An rtdb.ini has no item names: DB_item_name gives "item<ID>", or the names
 * of the rtdb_user.h that $CANHIL_RTDB_USER_H names (checked against the ini).
 *
 * Environment:
 *   AGENT              this process's agent number (required by DB_init)
 *   RTDB_KEY           base System V key (default: derived from the user id),
 *                      so that several independent teams or test runs share a
 *                      machine; agent N's segment has key RTDB_KEY + N
 *   SECOND_RTDB        set (not "0"): DB_init joins the second team's set
 *                      (keys RTDB_KEY + 64 + N), as CAMBADA's simulator names it
 *   RTDB_VERBOSE       1 prints what DB_init does to stderr
 *   CANHIL_RTDB_INI    librtdb.so: the rtdb.ini when the program names none
 *   CANHIL_RTDB_USER_H the rtdb_user.h that names an rtdb.ini's items
 */
#ifndef CANHIL_RTDB_RTDB_H
#define CANHIL_RTDB_RTDB_H

/* Relative paths: the CAMBADA-named headers installed next to canhil/, never
 * another library's files of the same names on the include path. */
#include "../../rtdb_api.h"
#include "../../rtdb_comm.h"
#include "../../rtdb_sim.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* --- canhil extensions ---------------------------------------------------- */

/* Number of agents and items in the item table (item ids are 0 .. count - 1;
 * an rtdb.ini may leave ids out: they have no size and no owner). 0 when the
 * table cannot be read (the reason on stderr). */
int DB_agent_count(void);
int DB_item_count(void);
/* Names from the table (NULL when out of range). */
const char* DB_agent_name(int agent);
const char* DB_item_name(int id);
/* Size in bytes of item `id`, or -1 (out of range, or an id no agent has). */
int DB_item_size(int id);
/* 1 if agent `agent`'s schema has item `id` as shared, 0 as local, -1 neither. */
int DB_item_shared(int agent, int id);
/* Where the item table came from (a configuration file's path), or NULL. */
const char* DB_config_source(void);

/* The vision-to-agent wake-up: after writing VISION_INFO, the vision process
 * calls DB_signal_frame(space) (the agent's memory space: the agent, or N +
 * the agent in the second set); the agent blocks in DB_wait_frame until then
 * (or until timeout_ms passes; -1 waits forever). A POSIX named semaphore per
 * agent and key base. DB_wait_frame returns 0 when woken, 1 on timeout, -1 on
 * error. Several posts while the agent was busy wake it once. */
int DB_signal_frame(int space);
/* This process's memory space after DB_init: its agent, or N + its agent in
 * the second set (SECOND_RTDB); -1 before. What DB_put_in / DB_get_from take. */
int DB_space(void);
int DB_wait_frame(int timeout_ms);

/* The clock items are stamped and aged by in this process: CLOCK_MONOTONIC
 * unless set. A process that runs the robots in virtual time (canhil run
 * --virtual-time, with its handler and agent in process) sets its virtual
 * clock, so that ages are virtual-time ages. `now(context)` gives nanoseconds
 * from any start; the value it gives at this call is taken to be the
 * monotonic clock's at this call, so stamps from before and after compare.
 * NULL restores the monotonic clock. Other processes keep theirs: a run
 * faster than real time stamps ahead of it, and they read its items as 0 ms
 * old. Set-up: not while other threads use the database; `now` is then
 * called from whichever thread reads or writes an item, under no lock. */
void DB_set_clock(int64_t (*now)(void* context), void* context);

/* Bytes [offset, offset + size) of an item, as DB_get_from would give them
 * (one consistent write, under the same sequence lock), into `value`: a
 * client that needs a few fields of a large item (the ball from VISION_INFO)
 * copies those instead of the whole item. Returns the item's age in ms, or -1
 * (no such item or agent, or the range reaches past the item). */
int DB_get_part(int agent, int from_agent, int id, size_t offset, size_t size, void* value);

/* DB_put_in of a whole item image `value` that differs from what the slot
 * holds only inside `count` byte ranges, ranges[2i] the offset and
 * ranges[2i + 1] the length of range i: those are copied, in one write under
 * the sequence lock (a reader sees all of them or none), and the item is
 * stamped as by DB_put_in. For a writer that keeps an item's image and
 * changes a few parts of a large item (a vision frame's point lists); bytes
 * outside the ranges must already be in the slot (written from the same
 * image). Returns the item's size, or -1 (no such item or agent, a range past
 * the item, count < 0, life < 0). */
int DB_put_ranges(int agent, int to_agent, int id, const void* value, const size_t* ranges, int count, int life);

#ifdef __cplusplus
}
#endif

#endif
