# box_on_vcan.sh — guest script of the test socketcan_vm.scopekin_box (run by vm_run.sh in the VM;
# busybox sh).  scopekin-box runs on vcan0 (a real kernel CAN_RAW stack) with its EM tracker on a
# serial line (--serial: a pseudo-terminal fed by scopekin-vm-peer's tracker, 30 Hz per source);
# candump records the bus, canplayer replays the handle sensors' 1 kHz traffic (10 s, with the
# force cell silent for 0.3 s).  When the box has taken (or counted as dropped) every frame, the
# tracker pauses, two error frames are injected (bus-off, then restarted) and the box is stopped
# with SIGINT.  The host checks the files in /out with check_box_run.py.
# usage: box_on_vcan.sh INPUT_FRAMES   (the number of frames canplayer sends)
set -u

. /scopekin/guest_lib.sh   # wait_receivers, mark

total=$1
scopekin-vm-peer tracker --link /tmp/ttyEM0 --report /out/tracker.json 2>/out/tracker.err &
tracker=$!
wait_path /tmp/ttyEM0 || exit 1
# candump: a 4 MB receive buffer (root may force it), so that the observer keeps every frame even
# when a loaded machine stalls it; -d reports any frame it lost anyway (DROPCOUNT lines).
candump -d -r 4194304 -L vcan0,0:0,#FFFFFFFF > /out/candump.log &
dump=$!
scopekin-box --can vcan0 --serial /tmp/ttyEM0 --record /out/box_record.log \
  --stats /out/box_stats.json --fault-log /out/box_faults.csv 2> /out/box_stderr.log &
box=$!
wait_receivers rcvlist_all 1 || exit 1     # candump
wait_receivers rcvlist_sff 2 || exit 1     # the box's two input identifiers
mark start
canplayer -I /scopekin/handle_1khz.log
player=$?
mark traffic_end
# Wait until the box has read every frame or counted it as dropped (its progress line, once a
# second), however slow the machine: the checks then account for every frame.
tries=0
while :; do
  line=$(grep 'received=' /out/box_stderr.log | tail -n 1)
  received=$(echo "$line" | sed -n 's/.* received=\([0-9]*\) .*/\1/p')
  dropped=$(echo "$line" | sed -n 's/.* dropped=\([0-9]*\) .*/\1/p')
  [ $(( ${received:-0} + ${dropped:-0} )) -ge "$total" ] && break
  tries=$((tries + 1))
  [ $tries -ge 300 ] && { echo "the box took ${received:-?} + dropped ${dropped:-?} of $total frames in 30 s"; break; }
  usleep 100000
done
mark tracker_pause
kill -USR1 "$tracker"
sleep 0.1
# Error frames (bit 29 = CAN_ERR_FLAG): bus-off, then the controller restarted.
cansend vcan0 20000040#0000000000000000
sleep 0.05
cansend vcan0 20000100#0000000000000000
sleep 0.2
kill -INT "$box"
wait "$box"
box_status=$?
kill "$tracker"
wait "$tracker"
sleep 0.1
kill "$dump" 2>/dev/null
wait "$dump" 2>/dev/null
echo "canplayer=$player scopekin-box=$box_status" > /out/exit_status.txt
cat /out/exit_status.txt
tail -n 3 /out/box_stderr.log
# The logs come back over a slow serial line: compress them.
gzip -1 /out/candump.log /out/box_record.log
[ "$player" -eq 0 ] && [ "$box_status" -eq 0 ]
