/* AUTOGEN FILE : rtdb_user.h (a team's generated header, for the install test) */

#ifndef _TEAM_RTDB_USER_
#define _TEAM_RTDB_USER_

/* agents section */

#define BASE_STATION	0
#define ROBOT_1	1

#define N_AGENTS	2

/* items section */

#define ROBOT_WS	0
#define COACH_INFO	1
#define CMD_VEL	2

#define N_ITEMS	3

#endif

/* EOF : rtdb_user.h */
