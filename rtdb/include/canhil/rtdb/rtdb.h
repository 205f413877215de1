/* canhil/rtdb/rtdb.h — the real-time database (RTDB): a shared-memory
 * blackboard per robot, with the C API the CAMBADA laptop software calls.
 *
 * Each agent (robot or base station, numbered by their order in the
 * configuration's AGENTS list; the process's agent comes from the AGENT
 * environment variable) has its own System V shared-memory segment, readable
 * and writable by its owner only. It holds the agent's own items (the shared
 * and local items of its schema) and a copy of every other agent's shared
 * items, which the replicator (canhil rtdb replicate) keeps up to date.
 *
 * Every item carries the time it was written; readers get it as an age. A
 * write is never seen half done: items are sequence-locked. All functions are
 * thread-safe after DB_init / DB_init_all.
 *
 * Which items exist comes from a configuration file (AGENTS / ITEM / SCHEMA /
 * ASSIGNMENT; see docs/rtdb.md) turned into C by canhil-rtdb-gen at build
 * time: rtdb_user.h (item ids) and rtdb_config.c (the table this library
 * reads). Link canhil::rtdb for canhil's shipped configuration, or
 * canhil::rtdb_core plus your own generated rtdb_config.c.
 *
 * Environment:
 *   AGENT         this process's agent number (required by DB_init)
 *   RTDB_KEY      base System V key (default: derived from the user id), so
 *                 that several independent teams or test runs share a machine
 *   RTDB_VERBOSE  1 prints what DB_init does to stderr
 */
#ifndef CANHIL_RTDB_RTDB_H
#define CANHIL_RTDB_RTDB_H

#ifdef __cplusplus
extern "C" {
#endif

/* Attaches this process to its agent's database (AGENT), creating it when it
 * does not exist yet and reclaiming one left by a crashed run.
 * Returns 0, or -1 with a message on stderr saying what to do. */
int DB_init(void);

/* Detaches; the last process to detach from a segment removes it. */
void DB_free(void);

/* Writes item `id` of this agent. Returns 0, or -1 (not initialised, unknown
 * id, or an item this agent's schema does not have). */
int DB_put(int id, void* value);

/* Reads item `id` of agent `from_agent` (this agent's own item when
 * from_agent == Whoami(), else the replicated copy of that agent's shared
 * item) into `value`. Returns the item's age in ms, or -1 on error. An item
 * never written reads as zeros with its age counted from the database's
 * creation. */
int DB_get(int from_agent, int id, void* value);

/* This process's agent number, or -1 before DB_init. */
int Whoami(void);

/* For a process serving several robots (a simulator): after DB_init_all,
 * writes into agent `agent`'s database the item `id` of agent `to_agent`
 * (`agent` itself, or the copy of another agent's shared item), as if it was
 * written `life` ms ago. Returns 0 or -1. */
int DB_put_in(int agent, int to_agent, int id, void* value, int life);

/* Attaches to the databases of all agents (creating them as needed).
 * `second_rtdb` is accepted for compatibility and ignored. Returns 0 or -1. */
int DB_init_all(int second_rtdb);

/* Detaches from all agents' databases. */
void DB_free_all(int second_rtdb);

/* After DB_init_all: reads, from agent `agent`'s database, the item `id` of
 * agent `from_agent`. Returns the age in ms or -1. */
int DB_get_from(int agent, int from_agent, int id, void* value);

/* --- canhil extensions ---------------------------------------------------- */

/* Number of agents and items in the linked configuration. */
int DB_agent_count(void);
int DB_item_count(void);
/* Names from the configuration (NULL when out of range). */
const char* DB_agent_name(int agent);
const char* DB_item_name(int id);
/* Size in bytes of item `id`, or -1. */
int DB_item_size(int id);
/* 1 if agent `agent`'s schema has item `id` as shared, 0 as local, -1 neither. */
int DB_item_shared(int agent, int id);

/* The vision-to-agent wake-up: after writing VISION_INFO, the vision process
 * calls DB_signal_frame(agent); the agent blocks in DB_wait_frame until then
 * (or until timeout_ms passes; -1 waits forever). A POSIX named semaphore per
 * agent and RTDB_KEY. DB_wait_frame returns 0 when woken, 1 on timeout, -1 on
 * error. Several posts while the agent was busy wake it once. */
int DB_signal_frame(int agent);
int DB_wait_frame(int timeout_ms);

#ifdef __cplusplus
}
#endif

#endif
