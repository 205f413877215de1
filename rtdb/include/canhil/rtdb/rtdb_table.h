/* canhil/rtdb/rtdb_table.h — the item table the RTDB library reads: compiled
 * by canhil-rtdb-gen (rtdb_config.c) or read from a team's rtdb.ini at run
 * time. Not for application code. */
#ifndef CANHIL_RTDB_RTDB_TABLE_H
#define CANHIL_RTDB_RTDB_TABLE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const char* name;
  uint32_t size;   /* sizeof(datatype); 0: an id no agent has (rtdb.ini) */
  uint32_t period; /* replication period in replicator cycles */
} canhil_rtdb_item;

typedef struct {
  const char* name;
  /* Per item: 1 shared, 0 local, -1 not in this agent's schema. */
  const int8_t* membership;
} canhil_rtdb_agent;

typedef struct canhil_rtdb_table {
  uint32_t n_agents;
  uint32_t n_items;
  const canhil_rtdb_agent* agents;
  const canhil_rtdb_item* items;
  const char* source; /* the configuration file it was generated from */
} canhil_rtdb_table;

/* Defined by the generated rtdb_config.c. */
extern const canhil_rtdb_table canhil_rtdb_config;

/* Reads a table from an rtdb.ini (CAMBADA's runtime format) and, when
 * user_h is not NULL, the rtdb_user.h that names its agents and items
 * (#define NAME NUMBER; checked against the ini: an ini item or agent the
 * header does not name, or names otherwise, is an error; a header item no
 * agent has is kept, with size 0). Returns the table (free it with
 * canhil_rtdb_table_free), or NULL with "FILE:LINE: what is wrong; what to
 * do" in error. */
canhil_rtdb_table* canhil_rtdb_table_load(const char* ini, const char* user_h, char* error, size_t error_size);
void canhil_rtdb_table_free(canhil_rtdb_table* table);

#ifdef __cplusplus
}
#endif

#endif
