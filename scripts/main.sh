#!/usr/bin/env bash
# main.sh — the main job of the README: set everything up, build canhil and
# show it working on the shipped message set and a sample trace of one robot's
# bus (the full emulator demo grows here as the project does).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
bash scripts/build.sh plain >/dev/null
canhil=build/plain/app/canhil
echo "== the message set (frames/canhil.dbc)"
"$canhil" frames list
echo
echo "== a shipped trace of one robot's bus, decoded (frames/samples/one_robot.log)"
"$canhil" dump --log frames/samples/one_robot.log
echo
echo "== its timing and FTT compliance (canhil timing)"
"$canhil" timing frames/samples/one_robot.log
echo
echo "== physics: the ball-drop and drive calibration experiments (docs/physics.md)"
"$canhil" experiment ball-drop
echo
"$canhil" experiment drive
echo
echo "== vision: one frame of one robot among five, drawn in build/plain/vision.svg"
"$canhil" experiment vision --svg build/plain/vision.svg
echo
echo "== the demo: one robot, the whole loop in virtual time (emulated nodes, physics, vision,"
echo "   the reference handler and agent); the robot drives to the ball and kicks it toward the goal"
"$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --trace build/plain/demo.log \
  --world-log build/plain/demo.csv
echo
echo "== the demo's timing report (canhil timing build/plain/demo.log)"
"$canhil" timing build/plain/demo.log
echo
echo "== the demo in real time on vcan (this machine's, or the VM runner's where the kernel has no CAN):"
echo "   canhil run, canhil-hwcomm and canhil-agent as three processes; timing of the live bus at the end"
bash vcan_setup/with-vcan.sh -- bash scripts/demo.sh 20
