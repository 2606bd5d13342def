# display_on_vcan.sh — guest script of the test socketcan_vm.scopekin_display (run by vm_run.sh in
# the VM; busybox sh).  scopekin-box runs on vcan0 and `scopekin display --can vcan0` beside it
# listens to the bus; canplayer replays the handle sensors' 1 kHz traffic; busybox wget reads the
# display's page and its event stream.  The host checks the files in /out with
# check_display_run.py.
# usage: display_on_vcan.sh      (SCOPEKIN_VIEW_ASSETS: the page's scripts, copied by the host)
set -u

. /scopekin/guest_lib.sh   # wait_receivers, wait_path

export SCOPEKIN_VIEW_ASSETS=/scopekin/assets
scopekin-box --can vcan0 --quiet 2> /out/box_stderr.log &
box=$!
scopekin display --can vcan0 --no-browser --port 8765 --quiet > /out/display.txt 2> /out/display_stderr.log &
display=$!
wait_receivers rcvlist_sff 2 || exit 1     # the box's two input identifiers
wait_receivers rcvlist_all 1 || exit 1     # the display: every frame
tries=0
until grep -q 'view at' /out/display.txt; do
  tries=$((tries + 1))
  [ $tries -ge 200 ] && { echo "the display did not start"; cat /out/display_stderr.log; exit 1; }
  usleep 50000
done
canplayer -I /scopekin/handle.log
player=$?
sleep 0.5
wget -q -O /out/page.html http://127.0.0.1:8765/
page=$?
# The live stream does not end while the bus is heard: read it for 5 s.
timeout 5 wget -q -O /out/events.txt http://127.0.0.1:8765/events
kill -INT "$display"
wait "$display"
display_status=$?
kill -INT "$box"
wait "$box"
box_status=$?
echo "canplayer=$player page=$page scopekin-display=$display_status scopekin-box=$box_status" > /out/exit_status.txt
cat /out/exit_status.txt
cat /out/display.txt
gzip -1 /out/events.txt /out/page.html
[ "$player" -eq 0 ] && [ "$page" -eq 0 ] && [ "$display_status" -eq 0 ] && [ "$box_status" -eq 0 ]
