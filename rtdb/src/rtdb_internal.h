/* What the RTDB library's C files share; not installed. */
#ifndef CANHIL_RTDB_INTERNAL_H
#define CANHIL_RTDB_INTERNAL_H

#include "canhil/rtdb/rtdb_table.h"

/* Agents one table may have (CAMBADA's MAX_AGENTS, in rtdbdefs.h, is 7). */
#define CANHIL_RTDB_MAX_AGENTS 64

/* The second set's (team's) keys: the first's plus this (see rtdb.c). */
#define CANHIL_RTDB_SET_STRIDE CANHIL_RTDB_MAX_AGENTS

/* The API of librtdb.so, which is built with hidden visibility: only what
 * carries this is exported. */
#define RTDB_EXPORT __attribute__((visibility("default")))

/* The table linked into the program (rtdb_linked_table.c: the generated
 * canhil_rtdb_config), or NULL when the library reads an rtdb.ini at init
 * (rtdb_runtime_table.c, librtdb.so). */
const canhil_rtdb_table* canhil_rtdb_linked_table(void);

#endif
