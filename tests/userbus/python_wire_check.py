"""A program on a timed interface of the user-space bus (1 Mbit/s, vcan0),
with its own socket calls and with python-can, unchanged: its echo comes at
the frame's end of frame with MSG_CONFIRM, a full transmit queue answers
ENOBUFS, python-can reads the controller's error frames, and a socket opened
after the others closed hears the wire. Another program
(candump) acknowledges its frames. argv[1]: the canhil program, for the fault.
Prints what it saw; exit status 0 when all of it holds."""
import errno
import socket
import struct
import subprocess
import sys
import time

import can

SO_TIMESTAMPNS = 35  # asm-generic/socket.h (the socket module does not name it)
FRAME = struct.pack("=IB3x8s", 0x123, 8, bytes(8))
ok = True

s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
s.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_RECV_OWN_MSGS, 1)
s.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
s.bind(("vcan0",))
before = time.time_ns()
s.send(FRAME)
data, anc, flags, _ = s.recvmsg(16, 64)
stamp = 0
for level, kind, value in anc:
    if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
        sec, nsec = struct.unpack("=qq", value[:16])
        stamp = sec * 1_000_000_000 + nsec
confirm = bool(flags & socket.MSG_CONFIRM)
dontroute = bool(flags & socket.MSG_DONTROUTE)
# 8 zero bytes at 1 Mbit/s: 111 bits + stuffing, less the intermission: over 100 us after the write.
late_us = (stamp - before) / 1000
print(f"echo: MSG_CONFIRM {confirm}, MSG_DONTROUTE {dontroute}, stamped {late_us:.0f} us after the write")
ok = ok and confirm and dontroute and data == FRAME and late_us >= 100

# Nobody acknowledges for a while: nothing leaves the queue, so exactly the
# writes past txqueuelen are refused, however slowly this program writes (a
# loaded machine's python may write slower than the wire sends).
subprocess.run([sys.argv[1], "bus", "fault", "vcan0", "noack:*@0+60"], check=True, capture_output=True)
s.setblocking(False)
refused = 0
for _ in range(2000):
    try:
        s.send(FRAME)
    except OSError as e:
        if e.errno != errno.ENOBUFS:
            raise
        refused += 1
subprocess.run([sys.argv[1], "bus", "fault", "vcan0", "clear"], check=True, capture_output=True)
print(f"ENOBUFS: {refused} of 2000 writes at once (txqueuelen 10), never before 10 were queued")
ok = ok and refused == 1990
s.close()
time.sleep(0.1)

bus = can.interface.Bus(channel="vcan0", interface="socketcan")
subprocess.run([sys.argv[1], "bus", "fault", "vcan0", "noack:*@0+0.5"], check=True, capture_output=True)
bus.send(can.Message(arbitration_id=0x321, data=[1, 2, 3], is_extended_id=False))
errors = []
deadline = time.monotonic() + 2
while time.monotonic() < deadline and len(errors) < 3:
    m = bus.recv(timeout=0.5)
    if m is not None and m.is_error_frame:
        errors.append(m)
bus.shutdown()
if errors:
    m = errors[0]
    print(f"python-can: {len(errors)} error frames, the first 0x{m.arbitration_id:X} {list(m.data)}")
ok = ok and len(errors) >= 3 and all(m.arbitration_id & 0x20 for m in errors)  # CAN_ERR_ACK

# This process's sockets have all closed: a new one hears another program's
# frames (its old controller once made the new one miss them all).
time.sleep(0.5)  # the fault's half second over
r = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
r.settimeout(2)
r.bind(("vcan0",))
subprocess.run(["cangen", "vcan0", "-n", "3", "-g", "5", "-I", "77", "-L", "2"], check=True)
heard = 0
try:
    while heard < 3:
        if struct.unpack("=I", r.recv(16)[:4])[0] == 0x77:
            heard += 1
except socket.timeout:
    pass
r.close()
print(f"a socket opened after the others closed: heard {heard} of 3 frames")
ok = ok and heard == 3
sys.exit(0 if ok else 1)
