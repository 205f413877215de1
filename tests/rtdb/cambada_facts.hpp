// tests/rtdb/cambada_facts.hpp — the public CAMBADA RTDB items (GitHub
// CAMBADA/cambada-pub 1.0) as C structs, declared for canhil's tests from
// the facts of its headers (HWcomm_rtdb.h, VisionInfo.h, CoachInfo.h,
// Robot.h, ...): member names, types, order, and the sizes and offsets g++ 12
// gives on x86_64. Written here, not copied. Enums are 4-byte ints, `Vec`
// two floats. The static_asserts pin the published sizes and offsets.
#pragma once

#include <cstddef>

namespace facts {
struct Vec {
  float x, y;
};
struct RadialSensor {
  int nPoints;
  Vec point[500];
};
struct BallSensor {
  Vec position;
};
struct VisionInfo {
  RadialSensor obstacles, lines;
  BallSensor ball[5];
  int nBalls;
};
struct BallFrontSensor {
  Vec position;
  float height;
  int cyclesNotVisible;
};
struct FrontVisionInfo {
  BallFrontSensor ball[5];
};
struct CMD_Vel {
  float vx, vy, va;
  bool smallAdjustment;
};
struct CMD_Pos {
  float px, py, pa, dx, dy, da;
};
struct CMD_Kicker {
  unsigned char power, engLvlHigh, engLvlLow;
};
struct CMD_Grabber {
  unsigned char mode;
};
struct CMD_Info {
  unsigned short Voltage_logic, Voltage_power12, Voltage_power24, Kicker_voltage;
  bool justKicked;
};
struct CMD_HWerrors {
  unsigned short error_count[5][8];
};
struct CMD_Imu {
  int compass, yaw, rawYaw;
};
struct CMD_Grabber_Info {
  unsigned int leftArm, rightArm;
  bool leftHandicapped, rightHandicapped;
};
struct CMD_Grabber_Config {
  int configId;
};
struct PlayerInfo {
  int role, teamColor, goalColor;
  bool roleAuto, running, coaching;
  float orientation;
  Vec pos;
  int number;
};
struct CoachInfo {
  PlayerInfo playerInfo[6];
  int changePositionSN[6];
  int gameState, ourGoals, theirGoals, time;
  bool manualFormation;
  int half;
  char taxiRobotSN[6];
  Vec taxiPos;
  bool taxiOri;
};
struct FormationInfo {
  int formationIdFreePlay, formationIdSP;
  Vec position[6];
  int posId[6];
  bool cover[6];
};
struct Ball {
  Vec pos, posRel, vel;
  float height;
  bool own, engaged, visible, airborne, hasMoved;
};
struct Line {
  Vec p1, p2;
};
struct ObstacleInfo {
  Vec absCenter;
  unsigned char id;
};
struct Robot {
  int number, behaviour, role;
  int coordinationFlag[2];
  int currentGameState;
  Vec coordinationVec;
  int teamColor, goalColor;
  unsigned char nObst;
  char stuck;
  bool roleAuto, running, coaching, justKicked, handicappedGrabber;
  unsigned char opponentDribbling;
  float battery[3];
  float orientation, angVelocity;
  Vec debugPoints[4];
  Vec pos, vel;
  Ball ball;
  Line passLine;
  ObstacleInfo obstacles[20];
};
struct LaptopInfo {
  char status, charge;
};
struct KickCalibAppData {
  int robotNumber, power;
  float distance;
  bool active, kick;
};
struct KickCalibRobData {
  bool stopped, kicked;
  float distance;
  int power;
};
struct CellVal {
  Vec pos;
  float val;
};
struct GridView {
  int count;
  CellVal grid[5000];
};
struct CoachLogRobotsInfo {
  Robot robots[6];
};
struct CoachLogModeFlag {
  bool log;
};

// The published sizes and some published offsets: a slip in the
// declarations above cannot pass unnoticed.
static_assert(sizeof(VisionInfo) == 8052 && offsetof(VisionInfo, lines) == 4004 && offsetof(VisionInfo, ball) == 8008 &&
              offsetof(VisionInfo, nBalls) == 8048);
static_assert(sizeof(FrontVisionInfo) == 80 && sizeof(CMD_Vel) == 16 && sizeof(CMD_Pos) == 24);
static_assert(sizeof(CMD_Kicker) == 3 && sizeof(CMD_Grabber) == 1 && sizeof(CMD_Info) == 10);
static_assert(sizeof(CMD_HWerrors) == 80 && sizeof(CMD_Imu) == 12 && sizeof(CMD_Grabber_Info) == 12);
static_assert(sizeof(CMD_Grabber_Config) == 4 && sizeof(PlayerInfo) == 32 && offsetof(PlayerInfo, running) == 13);
static_assert(sizeof(CoachInfo) == 260 && offsetof(CoachInfo, gameState) == 216 && offsetof(CoachInfo, half) == 236 &&
              offsetof(CoachInfo, taxiPos) == 248 && offsetof(CoachInfo, taxiOri) == 256);
static_assert(sizeof(FormationInfo) == 88 && offsetof(FormationInfo, cover) == 80);
static_assert(sizeof(Ball) == 36 && sizeof(Robot) == 408 && offsetof(Robot, ball) == 116 &&
              offsetof(Robot, obstacles) == 168);
static_assert(sizeof(LaptopInfo) == 2 && sizeof(KickCalibAppData) == 16 && sizeof(KickCalibRobData) == 12);
static_assert(sizeof(GridView) == 60004 && sizeof(CoachLogRobotsInfo) == 2448 && sizeof(CoachLogModeFlag) == 1);
}  // namespace facts
