/* rtdb.h — what a CAMBADA program includes to use the RTDB: the item and agent
 * numbers of its configuration (rtdb_user.h, the team's generated header,
 * found on the include path) and the calls (rtdb_api.h). canhil's own header
 * with CAMBADA's name. Unlike CAMBADA's, it declares no item types: the team's
 * own headers do (CAMBADA's HWcomm_rtdb.h), and it compiles as C and C++. */
#ifndef CANHIL_RTDB_COMPAT_RTDB_H
#define CANHIL_RTDB_COMPAT_RTDB_H

#include "rtdb_api.h"
#include "rtdb_user.h"

#endif
