# display_on_vcan.sh — guest script of the tests socketcan_vm.scopekin_display and
# socketcan_vm.scopekin_box_view (run by vm_run.sh in the VM; busybox sh).  scopekin-box runs on
# vcan0 and `scopekin display --can vcan0` beside it listens to the bus — started by hand
# (display), or by the box itself with `scopekin-box --view` (box-view); canplayer replays the
# handle sensors' 1 kHz traffic; busybox wget reads the display's page and its event stream.  The
# host checks the files in /out with check_display_run.py.
# usage: display_on_vcan.sh [display|box-view]   (SCOPEKIN_VIEW_ASSETS: the page's scripts)
set -u

. /scopekin/guest_lib.sh   # wait_receivers, wait_path

mode=${1:-display}
export SCOPEKIN_VIEW_ASSETS=/scopekin/assets
if [ "$mode" = box-view ]; then
  # A display program that is not there: refused with the reason, exit 2, before the box runs.
  scopekin-box --can vcan0 --quiet --view --no-browser --display-program /nonexistent/scopekin \
    2> /out/refusal.txt
  echo "refusal=$?" > /out/refusal_status.txt
  # A display that ends on its own (its port taken): the box says so and goes on without it.
  # 8 s: on a loaded host (TCG, the asan build, a long run beside it) a box run for 2.5 s ended
  # before its display had found the port taken and said so (363 periods, nothing said).
  busybox httpd -p 127.0.0.1:8766 -h /tmp
  scopekin-box --can vcan0 --quiet --view --no-browser --view-port 8766 --duration-s 8 \
    --stats /out/box_stats_busy.json > /out/busy.txt 2> /out/busy_stderr.log
  echo "busy=$?" >> /out/refusal_status.txt
  scopekin-box --can vcan0 --quiet --view --no-browser --view-port 8765 --stats /out/box_stats.json \
    > /out/display.txt 2> /out/box_stderr.log &
  box=$!
  display=
else
  scopekin-box --can vcan0 --quiet 2> /out/box_stderr.log &
  box=$!
  scopekin display --can vcan0 --no-browser --port 8765 --quiet > /out/display.txt 2> /out/display_stderr.log &
  display=$!
fi
wait_receivers rcvlist_sff 2 || exit 1     # the box's two input identifiers
wait_receivers rcvlist_all 1 || exit 1     # the display: every frame
tries=0
until grep -q 'view at' /out/display.txt; do
  tries=$((tries + 1))
  [ $tries -ge 200 ] && { echo "the display did not start"; cat /out/display_stderr.log /out/box_stderr.log 2> /dev/null; exit 1; }
  usleep 50000
done
canplayer -I /scopekin/handle.log
player=$?
sleep 0.5
wget -q -O /out/page.html http://127.0.0.1:8765/
page=$?
# The live stream does not end while the bus is heard: read it for 5 s.
timeout 5 wget -q -O /out/events.txt http://127.0.0.1:8765/events
if [ -n "$display" ]; then
  kill -INT "$display"
  wait "$display"
  display_status=$?
fi
kill -INT "$box"
wait "$box"
box_status=$?
if [ -z "$display" ]; then
  # The box stopped its display (SIGTERM) and says in its statistics how it ended.
  grep -q '"how": "exit status 0"' /out/box_stats.json && display_status=0 || display_status=1
  grep -q '"ended_on_its_own": false' /out/box_stats.json || display_status=1
fi
echo "canplayer=$player page=$page scopekin-display=$display_status scopekin-box=$box_status" > /out/exit_status.txt
cat /out/exit_status.txt
cat /out/display.txt
gzip -1 /out/events.txt /out/page.html
[ "$player" -eq 0 ] && [ "$page" -eq 0 ] && [ "$display_status" -eq 0 ] && [ "$box_status" -eq 0 ]
