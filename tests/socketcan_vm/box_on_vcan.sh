# box_on_vcan.sh — guest script of the test socketcan_vm.scopekin_box (run by vm_run.sh in the VM;
# busybox sh).  scopekin-box runs on vcan0 (a real kernel CAN_RAW stack), candump records the
# bus, canplayer replays the handle sensors' 1 kHz traffic (10 s, with the force cell silent for
# 0.3 s), then two error frames are injected (bus-off, then restarted) and the box is stopped
# with SIGINT.  The host checks the files in /out with check_box_run.py.
set -u

. /scopekin/guest_lib.sh   # wait_receivers

candump -L vcan0,0:0,#FFFFFFFF > /out/candump.log &
dump=$!
scopekin-box --can vcan0 --record /out/box_record.log --stats /out/box_stats.json --quiet &
box=$!
wait_receivers rcvlist_all 1 || exit 1     # candump
wait_receivers rcvlist_sff 2 || exit 1     # the box's two input identifiers
canplayer -I /scopekin/handle_1khz.log
player=$?
sleep 0.2
# Error frames (bit 29 = CAN_ERR_FLAG): bus-off, then the controller restarted.
cansend vcan0 20000040#0000000000000000
sleep 0.05
cansend vcan0 20000100#0000000000000000
sleep 0.2
kill -INT "$box"
wait "$box"
box_status=$?
sleep 0.1
kill "$dump" 2>/dev/null
wait "$dump" 2>/dev/null
echo "canplayer=$player scopekin-box=$box_status" > /out/exit_status.txt
cat /out/exit_status.txt
# The logs come back over a slow serial line: compress them.
gzip -1 /out/candump.log /out/box_record.log
[ "$player" -eq 0 ] && [ "$box_status" -eq 0 ]
