/* rtdb_user.h of a CAMBADA-like team, for canhil's tests: CAMBADA's item
 * names and sizes (docs/layouts.md, the cambada layout), its own numbering. */
#ifndef CANHIL_TEST_CAMBADA_LIKE_RTDB_USER_H
#define CANHIL_TEST_CAMBADA_LIKE_RTDB_USER_H

/* agents section */

#define BASE_STATION	0
#define CAMBADA_1	1
#define CAMBADA_2	2
#define CAMBADA_3	3
#define CAMBADA_4	4
#define CAMBADA_5	5
#define CAMBADA_6	6

#define N_AGENTS	7

/* items section */

#define ROBOT_WS	0
#define COACH_INFO	1
#define VISION_INFO	2
#define CMD_VEL	3
#define LAST_CMD_VEL	4
#define CMD_POS	5
#define CMD_KICKER	6
#define CMD_GRABBER	7
#define CMD_INFO	8
#define CMD_HWERRORS	9
#define CMD_IMU	10
#define CMD_SYNCIMU	11
#define CMD_GRABBER_INFO	12
#define FORMATION_INFO	13

#define N_ITEMS	14

#endif
