#!/bin/busybox sh
# Init of the canhil VM (PID 1 inside the initramfs built by vm-run.sh).
# Loads the modules, mounts the host's root over 9p, creates the vcan
# interfaces and runs the job in a chroot of the host's filesystem.
/bin/busybox mkdir -p /proc /sys /dev /host /tmp
/bin/busybox mount -t proc proc /proc
/bin/busybox mount -t sysfs sys /sys
/bin/busybox mount -t devtmpfs dev /dev
/bin/busybox --install -s /bin
export PATH=/bin

job= ifaces=1
for word in $(cat /proc/cmdline); do
  case "$word" in
    canhil.job=*) job="${word#canhil.job=}" ;;
    canhil.ifaces=*) ifaces="${word#canhil.ifaces=}" ;;
  esac
done

fail() { echo "canhil-vm: $*" > /dev/ttyS1; echo "canhil-vm: $*"; poweroff -f; }

while read -r module; do
  insmod "/modules/$module" || fail "insmod $module failed"
done < /modules/order

mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000,cache=loose hostroot /host || fail "cannot mount the host filesystem over 9p"
mount -t proc proc /host/proc
mount -t sysfs sys /host/sys
mount -o bind /dev /host/dev
mkdir -p /host/dev/shm /host/dev/pts
mount -t tmpfs shm /host/dev/shm
mount -t devpts devpts /host/dev/pts

ip link set lo up
i=0
while [ "$i" -lt "$ifaces" ]; do
  ip link add dev "vcan$i" type vcan || fail "cannot create vcan$i"
  ip link set "vcan$i" up
  i=$((i + 1))
done

stty -F /dev/ttyS1 raw -echo -onlcr 2>/dev/null
[ -n "$job" ] || fail "no job given on the kernel command line"
chroot /host /bin/bash "$job" < /dev/null > /dev/ttyS1 2>&1
echo "$?" > "/host${job%/job.sh}/status"
sync
poweroff -f
