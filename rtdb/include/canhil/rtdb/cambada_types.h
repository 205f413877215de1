/* canhil/rtdb/cambada_types.h — the layouts of the RTDB items the laptop's
 * handler, vision and agent exchange, as in the public CAMBADA RTDB headers
 * (fields in order, C types). Units: m, rad, m/s, rad/s unless said. */
#ifndef CANHIL_RTDB_CAMBADA_TYPES_H
#define CANHIL_RTDB_CAMBADA_TYPES_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Read by the handler, sent as M6_1 + M6_2. Robot frame, y forward. */
typedef struct {
  float vx, vy, va;
  bool smallAdjustment;
} CMD_Vel;

/* Read by the handler, sent once as M7, then `power` is reset to 0.
 * power: bit7 = 1 low (direct) kick, 0 high (lob); bits 0-6 power (capped to 50). */
typedef struct {
  unsigned char power, engLvlHigh, engLvlLow;
} CMD_Kicker;

/* Read by the handler, sent in M7 (grabber_mode 0..100). */
typedef struct {
  unsigned char mode;
} CMD_Grabber;

/* Written from M4_1 + M4_2: odometry pose; d* = change since the previous. */
typedef struct {
  float px, py, pa, dx, dy, da;
} CMD_Pos;

/* Written from M2 (voltages, in 10 mV) and M9 (justKicked; Kicker_voltage
 * from the capacitor, also in 10 mV). */
typedef struct {
  unsigned short Voltage_logic, Voltage_power12, Voltage_power24, Kicker_voltage;
  bool justKicked;
} CMD_Info;

/* Written from M8: compass = heading in whole degrees [0, 360), yaw = heading
 * in 0.01 deg, rawYaw = M8.raw. */
typedef struct {
  int compass, yaw, rawYaw;
} CMD_Imu;

/* Written from M10 and the handler's own counts; see docs/rtdb.md for the cells. */
typedef struct {
  unsigned short error_count[5][8];
} CMD_HWerrors;

/* canhil: written from M9 (the barrier and the grabber as Pic_base reports them). */
typedef struct {
  unsigned char ballEngaged, grabberMode;
} CMD_Grabber_Info;

/* canhil: the agent asks the handler to set (command 0) or reset (command 1)
 * the odometry pose: the handler sends M5_1 + M5_2 once and clears `pending`. */
typedef struct {
  float px, py, pa;
  unsigned char command, pending;
} CMD_SetPose;

#define MAX_POINTS 300
#define MAX_BALLS 5

/* A point in the robot frame, metres (x right, y forward). CAMBADA calls its
 * own two-float point `Vec` (geom/Vec.h, a C++ class with the same layout);
 * this header keeps its name apart so that both can meet in one program. */
typedef struct {
  float x, y;
} canhil_vec2;

typedef struct {
  int nPoints;
  canhil_vec2 point[MAX_POINTS];
} PointList;

/* Written by the vision (emulator) at 30 Hz. */
typedef struct {
  PointList obstacles;
  PointList linePoints;
  canhil_vec2 ball[MAX_BALLS];
  int nBalls;
} VisionInfo;

/* Shared between robots (replicated): a robot's own summary for its team. */
typedef struct {
  float x, y, orientation;
  int running;
  unsigned int frame;
} RobotWS;

/* Shared by the base station: the coach's orders. */
typedef struct {
  int gameState;
  int formation;
} CoachInfo;

#ifdef __cplusplus
}
#endif

#endif
