# guest_lib.sh — shell functions shared by the guest scripts (busybox sh); vm_run.sh callers copy
# it to /scopekin/guest_lib.sh (--file) and the scripts source it.

# wait_receivers LIST N: waits until N CAN_RAW receivers on vcan0 are registered in
# /proc/net/can/LIST (their sockets are bound), so that no frame is sent before they listen.
# LIST: rcvlist_all (filter 0:0), rcvlist_sff (single standard ids), rcvlist_err (error filter),
# rcvlist_inv (inverted filter).  Gives up after 10 s.
wait_receivers() {
  list=$1 want=$2 tries=0
  while :; do
    have=$(grep -c '^ *vcan0 .* raw$' "/proc/net/can/$list" 2>/dev/null)
    [ "${have:-0}" -ge "$want" ] && return 0
    tries=$((tries + 1))
    [ $tries -ge 200 ] && { echo "timeout waiting for $want receiver(s) in $list"; return 1; }
    usleep 50000
  done
}

# wait_path PATH: waits until PATH exists (e.g. the EM tracker's serial link).  Gives up after 10 s.
wait_path() {
  tries=0
  while [ ! -e "$1" ]; do
    tries=$((tries + 1))
    [ $tries -ge 200 ] && { echo "timeout waiting for $1"; return 1; }
    usleep 50000
  done
}

# mark NAME: appends "NAME <CLOCK_MONOTONIC µs>" to /out/marks.txt (scopekin-vm-peer now): when the
# script caused or ended a fault, on the clock of the box's periods and --fault-log.
mark() {
  echo "$1 $(scopekin-vm-peer now)" >> /out/marks.txt
}
