# box_faults_on_vcan.sh — guest script of the test socketcan_vm.scopekin_box_faults (run by
# vm_run.sh in the VM; busybox sh).  scopekin-box runs on vcan0 with its EM tracker on a serial
# line while scopekin-vm-peer plays both handle sensors at 1 kHz on the monotonic clock (a 30 s
# log, stopped after the last fault); meanwhile the script causes, one after the other:
#   netdown   `ip link set vcan0 down` for 0.3 s (every send fails with ENETDOWN), then up;
#   nobufs    a root qdisc that takes nothing (`tc qdisc add dev vcan0 root pfifo limit 0`: every
#             send fails with ENOBUFS, the send queue is full) for 0.3 s, then removed (iproute2's
#             tc, by its path: busybox sh would run its own tc applet, which has no pfifo);
#   unplug    the EM tracker's pseudo-terminal closed (an adapter unplugged: the box reads a
#             hang-up) and, 0.4 s later, a new one linked at the same path (plugged back in);
#   stepfwd   the wall clock stepped an hour forward, and 0.5 s later
#   stepback  an hour back: by the player (SIGUSR1 / SIGUSR2, clock_settime between two frames;
#             `kill` is a shell builtin), so that no program starts near the step (under TCG a
#             program's start takes the only CPU for ~0.1 s and would pause the inputs);
#   stall     the box stopped (SIGSTOP) for 1 s while the player goes on, then continued: the
#             kernel drops what its socket buffer cannot hold, the box's timer skips ~200
#             periods; both must be counted, flagged and reported, and the box recovers.
# Each cause and its end is marked on CLOCK_MONOTONIC in /out/marks.txt (NAME_begin before the
# command, NAME_done after it; the end as NAME_end_begin / NAME_end_done; the steps in the
# player's report); the box writes its fault state per change to /out/box_faults.csv.  The host
# checks them with check_box_faults.py.
set -u

. /scopekin/guest_lib.sh   # wait_receivers, wait_path, mark

cause() {   # cause NAME COMMAND...: runs COMMAND between the marks NAME_begin and NAME_done
  name=$1
  shift
  mark "${name}_begin"
  "$@" || echo "FAILED ($?): $*"
  mark "${name}_done"
}

scopekin-vm-peer tracker --link /tmp/ttyEM0 --report /out/tracker1.json 2>/out/tracker1.err &
tracker=$!
wait_path /tmp/ttyEM0 || exit 1
candump -D -d -r 4194304 -L vcan0,0:0,#FFFFFFFF > /out/candump.log 2>/out/candump.err &
dump=$!
scopekin-box --can vcan0 --serial /tmp/ttyEM0 --record /out/box_record.log \
  --stats /out/box_stats.json --fault-log /out/box_faults.csv 2> /out/box_stderr.log &
box=$!
wait_receivers rcvlist_all 1 || exit 1     # candump
wait_receivers rcvlist_sff 2 || exit 1     # the box's two input identifiers
mark start
scopekin-vm-peer play --can vcan0 --log /scopekin/handle.log --report /out/player.json &
player=$!

sleep 1
cause netdown ip link set vcan0 down
sleep 0.3
cause netdown_end ip link set vcan0 up
sleep 1.2
cause nobufs /usr/local/sbin/tc qdisc add dev vcan0 root pfifo limit 0
sleep 0.3
cause nobufs_end /usr/local/sbin/tc qdisc del dev vcan0 root
sleep 1.2
mark unplug_begin
kill "$tracker"
wait "$tracker"
mark unplug_done
sleep 0.4
mark unplug_end_begin
scopekin-vm-peer tracker --link /tmp/ttyEM0 --report /out/tracker2.json 2>/out/tracker2.err &
tracker=$!
wait_path /tmp/ttyEM0
mark unplug_end_done
sleep 1.2
kill -USR1 "$player"    # stepfwd
sleep 0.5
kill -USR2 "$player"    # stepback
sleep 0.5
mark stall_begin
kill -STOP "$box"       # the box stalls for 1 s: ~2000 frames for a ~475-frame socket buffer
sleep 1
kill -CONT "$box"
mark stall_end
sleep 1
mark traffic_end
kill "$player"   # the log lasts longer than the faults take, however slow the machine
wait "$player"
player_status=$?
sleep 1   # the box reads what waits in its socket (an asan box under TCG is slow to) before it stops
kill -INT "$box"
wait "$box"
box_status=$?
kill "$tracker"
wait "$tracker"
kill "$dump" 2>/dev/null
wait "$dump" 2>/dev/null
echo "player=$player_status scopekin-box=$box_status" > /out/exit_status.txt
cat /out/exit_status.txt /out/marks.txt
tail -n 3 /out/box_stderr.log
gzip -1 /out/candump.log /out/box_record.log
[ "$player_status" -eq 0 ] && [ "$box_status" -eq 0 ]
