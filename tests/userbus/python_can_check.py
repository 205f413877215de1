"""python-can's socketcan interface, unchanged, on interface vcan0: one bus
with a filter for 0x123, one without; five frames sent, one passes the filter.
Prints what it received; exit status 0 when exactly that frame arrived."""
import sys

import can

rx = can.interface.Bus(channel="vcan0", interface="socketcan",
                       can_filters=[{"can_id": 0x123, "can_mask": 0x7FF}])
tx = can.interface.Bus(channel="vcan0", interface="socketcan")
for i in range(5):
    tx.send(can.Message(arbitration_id=0x120 + i, data=[i, 1, 2], is_extended_id=False))
got = []
while True:
    m = rx.recv(timeout=0.5)
    if m is None:
        break
    got.append(m)
rx.shutdown()
tx.shutdown()
for m in got:
    print(f"python-can: {len(got)} of 5 frames through the filter, {hex(m.arbitration_id)} {list(m.data)} on {m.channel}")
sys.exit(0 if len(got) == 1 and got[0].arbitration_id == 0x123 and m.timestamp > 0 else 1)
