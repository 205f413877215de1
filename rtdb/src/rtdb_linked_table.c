/* The item table is the one linked into the program: canhil::rtdb's shipped
 * configuration, or the rtdb_config.c a team generated (canhil::rtdb_core). */
#include "rtdb_internal.h"

const canhil_rtdb_table* canhil_rtdb_linked_table(void) { return &canhil_rtdb_config; }
