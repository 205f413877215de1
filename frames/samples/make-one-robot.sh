#!/usr/bin/env bash
# make-one-robot.sh CANHIL > one_robot.log — writes the shipped sample trace:
# 300 ms of one robot's FTT-CAN bus while it drives forward at 0.5 m/s, laid
# out as the FTT master schedules it (TM at the start of each 10 ms EC,
# asynchronous window after it, synchronous window at the end of the EC).
# Values follow the robot's kinematics (wheel radius 0.0573 m, 30 000 counts
# per wheel turn, 5 ms motor tick): 180 counts per tick on wheels 1 and 2.
set -euo pipefail
canhil="$1"
enc() { "$canhil" frames encode "$@"; }
t0=1700000000
stamp() { printf '(%d.%06d)' $((t0 + $1 / 1000000)) $(($1 % 1000000)); }
line() { echo "$(stamp "$1") vcan0 $2"; }
enc1=0 enc2=0
for ((k = 0; k < 30; k++)); do
  base=$((k * 10000))
  bitmap=$(( (1 << 1) | (1 << 2) | (1 << 3) ))
  (( k % 3 == 0 )) && bitmap=$(( bitmap | 1 | (1 << 6) | (1 << 7) | (1 << 9) ))
  (( k % 5 == 0 )) && bitmap=$(( bitmap | (1 << 4) | (1 << 5) | (1 << 8) ))
  n=0; for ((b = 0; b < 10; b++)); do (( bitmap >> b & 1 )) && n=$((n + 1)); done
  window=$((n * 135 + 100))
  line $base "$(enc TM ec_counter=$k sync_bitmap=$bitmap sync_window_us=$window)"
  case $k in
    2) line $((base + 400)) "$(enc M5_1 x=0 y=0)"; line $((base + 540)) "$(enc M5_2 theta=0 command=reset)" ;;
    7) line $((base + 400)) "$(enc M2 v_logic=5.02 v_power12=12.31 v_power24=24.6 v_kicker=24.5)" ;;
    11) line $((base + 400)) "$(enc M10 alive=63 errors=0 node_state=1)" ;;
    20) line $((base + 400)) "$(enc M7 kick=178 grabber_mode=60 eng_lvl_high=0 eng_lvl_low=0)" ;;
  esac
  t=$((base + 10000 - window + 50))
  enc1=$((enc1 + 360)) enc2=$((enc2 - 360))
  for ((b = 0; b < 10; b++)); do
    (( bitmap >> b & 1 )) || continue
    case $b in
      0) f=$(enc M1 setpoint_1=180 setpoint_2=-180 setpoint_3=0 enable=1 seq=$((k / 3 % 256))) ;;
      1) f=$(enc M3_1 encoder=$enc1 delta=360 status=0 seq=$k) ;;
      2) f=$(enc M3_2 encoder=$enc2 delta=-360 status=0 seq=$k) ;;
      3) f=$(enc M3_3 encoder=0 delta=0 status=0 seq=$k) ;;
      4) f=$(enc M4_1 x=0 y=$(awk "BEGIN{print $k*0.005}")) ;;
      5) f=$(enc M4_2 theta=0 seq=$((k / 5))) ;;
      6) f=$(enc M6_1 vx=0 vy=0.5) ;;
      7) f=$(enc M6_2 va=0 small_adjustment=0 seq=$((k / 3 % 256))) ;;
      8) f=$(enc M8 heading=12.5 raw=125) ;;
      9) f=$(enc M9 ball_engaged=0 just_kicked=0 kicker_voltage=180 grabber=60) ;;
    esac
    line $t "$f"
    t=$((t + 135))
  done
done
