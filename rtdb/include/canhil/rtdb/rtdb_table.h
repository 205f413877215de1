/* canhil/rtdb/rtdb_table.h — the configuration table canhil-rtdb-gen writes
 * (rtdb_config.c) and the RTDB library reads. Not for application code. */
#ifndef CANHIL_RTDB_RTDB_TABLE_H
#define CANHIL_RTDB_RTDB_TABLE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const char* name;
  uint32_t size;   /* sizeof(datatype) */
  uint32_t period; /* replication period in replicator cycles */
} canhil_rtdb_item;

typedef struct {
  const char* name;
  /* Per item: 1 shared, 0 local, -1 not in this agent's schema. */
  const int8_t* membership;
} canhil_rtdb_agent;

typedef struct {
  uint32_t n_agents;
  uint32_t n_items;
  const canhil_rtdb_agent* agents;
  const canhil_rtdb_item* items;
  const char* source; /* the configuration file it was generated from */
} canhil_rtdb_table;

/* Defined by the generated rtdb_config.c. */
extern const canhil_rtdb_table canhil_rtdb_config;

#ifdef __cplusplus
}
#endif

#endif
