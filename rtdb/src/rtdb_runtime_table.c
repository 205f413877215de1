/* No table linked in (librtdb.so): DB_init / DB_init_all read an rtdb.ini,
 * as CAMBADA's library does (rtdb.c, rtdb_ini.c). */
#include <stddef.h>

#include "rtdb_internal.h"

const canhil_rtdb_table* canhil_rtdb_linked_table(void) { return NULL; }
