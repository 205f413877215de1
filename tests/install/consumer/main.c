/* Prints the linked RTDB configuration's agents and items: proves the
 * headers, the library and (for team_items) the generator came from the
 * install. */
#include <stdio.h>

#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"

int main(void) {
  printf("agents %d items %d first %s\n", DB_agent_count(), DB_item_count(), DB_item_name(0));
  return DB_item_count() > 0 ? 0 : 1;
}
