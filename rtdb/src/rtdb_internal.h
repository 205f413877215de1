/* What the RTDB library's C files share; not installed. */
#ifndef CANHIL_RTDB_INTERNAL_H
#define CANHIL_RTDB_INTERNAL_H

#include <stddef.h>

#include "canhil/rtdb/rtdb_table.h"

/* Agents one table may have (CAMBADA's MAX_AGENTS, in rtdbdefs.h, is 7). */
#define CANHIL_RTDB_MAX_AGENTS 64

/* The second set's (team's) keys: the first's plus this (see rtdb.c). */
#define CANHIL_RTDB_SET_STRIDE CANHIL_RTDB_MAX_AGENTS

/* Memory spaces a process may have: an agent of either set (see rtdb.c). */
#define CANHIL_RTDB_SETS 2
#define CANHIL_RTDB_SPACES (CANHIL_RTDB_SETS * CANHIL_RTDB_MAX_AGENTS)

/* The API of librtdb.so, which is built with hidden visibility: only what
 * carries this is exported. */
#define RTDB_EXPORT __attribute__((visibility("default")))

/* The table linked into the program (rtdb_linked_table.c: the generated
 * canhil_rtdb_config), or NULL when the library reads an rtdb.ini at init
 * (rtdb_runtime_table.c, librtdb.so). */
const canhil_rtdb_table* canhil_rtdb_linked_table(void);

/* The frame signal of a memory space (rtdb_frames.c): a named semaphore,
 * whose name `name_of` writes for `space` (0 <= space < CANHIL_RTDB_SPACES);
 * it is asked only when the semaphore is opened. Posts it unless already
 * posted, keeping it open when `keep` (a space this process has; threads may
 * post at once) or closing it again; 0, or -1 when it cannot be opened. */
typedef void (*canhil_rtdb_frames_name)(int space, char* name, size_t size);
int canhil_rtdb_frames_post(int space, canhil_rtdb_frames_name name_of, int keep);
/* Waits up to `timeout_ms` (< 0: for ever) for a post, keeping the semaphore
 * open, and takes every post made meanwhile: 0 when woken, 1 on timeout, -1
 * on error. */
int canhil_rtdb_frames_wait(int space, canhil_rtdb_frames_name name_of, int timeout_ms);
/* Closes the semaphore kept for `space`, if any: the process leaves the
 * space (no call on the space may overlap it). */
void canhil_rtdb_frames_forget(int space);

#endif
