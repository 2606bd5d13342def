#!/usr/bin/env bash
# run_box_vm_test.sh — the tests socketcan_vm.scopekin_box and socketcan_vm.scopekin_box_faults,
# host side.
#   traffic (socketcan_vm.scopekin_box):
#     1. make_handle_log.py writes the handle sensors' 1 kHz traffic (10 s, the force cell silent
#        for 0.3 s) from the DBC;
#     2. vm_run.sh boots the kernel, and box_on_vcan.sh runs scopekin-box on vcan0 with its EM
#        tracker on a serial line while canplayer replays the traffic and candump records the bus;
#     3. check_box_run.py checks the box's statistics, fault log and every frame it sent (decoded
#        with the DBC);
#     4. `scopekin replay` runs the box's own candump record (--record) through the firmware on
#        the host and must give back, frame for frame, the outputs the box sent in the VM.
#   faults (socketcan_vm.scopekin_box_faults):
#     1. 30 s of traffic without a silence (stopped after the faults); 2. box_faults_on_vcan.sh:
#     the interface down, a full
#     send queue, the tracker unplugged and back, the wall clock stepped; 3. check_box_faults.py.
#   display (socketcan_vm.scopekin_display): 4 s of traffic; scopekin-box and `scopekin display
#     --can vcan0` beside it (display_on_vcan.sh); busybox wget reads the page and the stream;
#     check_display_run.py.
#   box-view (socketcan_vm.scopekin_box_view): the same with the display started by the box itself,
#     `scopekin-box --view` (display_on_vcan.sh box-view); and a display program that is not there.
# All print the box's build (sanitizers), its overruns and the kernel's drops, and the time.
# usage: run_box_vm_test.sh traffic|faults|display|box-view PYTHON3 DBC OUT_DIR CACHE VM_TIMEOUT_S
#                           SCOPEKIN_BOX SCOPEKIN_VM_PEER CANPLAYER CANDUMP CANSEND TC SCOPEKIN
#                           [VIEW_ASSETS]
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
scenario=$1 python3=$2 dbc=$3 out=$4 cache=$5 vm_timeout=$6 box=$7 peer=$8 canplayer=$9
candump=${10} cansend=${11} tc=${12} scopekin=${13}
mkdir -p "$out"
work="$out.work"
rm -rf "$work" && mkdir -p "$work"
common=(--cache "$cache" --out "$out" --clean-out --timeout "$vm_timeout" --quiet
        --bin "$box:scopekin-box" --bin "$peer:scopekin-vm-peer" --bin "$candump" --bin "$cansend"
        --file "$here/guest_lib.sh:/scopekin/guest_lib.sh")
SECONDS=0
case $scenario in
  traffic)
    "$python3" "$here/make_handle_log.py" "$dbc" "$work/handle_1khz.log" > "$work/sent.json"
    echo "input: $(cat "$work/sent.json")"
    total=$("$python3" -c 'import json,sys; print(json.load(open(sys.argv[1]))["total"])' "$work/sent.json")
    bash "$here/vm_run.sh" "${common[@]}" --script "$here/box_on_vcan.sh" \
      --bin "$canplayer" --file "$work/handle_1khz.log:/scopekin/handle_1khz.log" -- "$total"
    echo "VM run (boot, 10 s of traffic, file transfer): ${SECONDS} s"
    "$python3" "$here/check_box_run.py" "$out" "$dbc" "$work/sent.json"
    gunzip -c "$out/box_record.log.gz" > "$work/box_record.log"
    "$scopekin" replay "$work/box_record.log" --out "$work/replay" --quiet
    "$python3" -c 'import json,sys; s=json.load(open(sys.argv[1])); print("replay of the box record: %d periods, %d output frames compared, %d differ" % (s["periods"], s["compared_frames"], s["differing_frames"])); sys.exit(0 if s["identical"] else 1)' "$work/replay/summary.json"
    ;;
  faults)
    "$python3" "$here/make_handle_log.py" "$dbc" "$work/handle.log" --duration 30 --gap 0 \
      --advance-mm-per-s 15 > "$work/sent.json"
    echo "input: $(cat "$work/sent.json")"
    bash "$here/vm_run.sh" "${common[@]}" --script "$here/box_faults_on_vcan.sh" \
      --bin "$tc:/usr/local/sbin/tc" --file "$work/handle.log:/scopekin/handle.log"
    echo "VM run (boot, ~9 s of traffic and faults, file transfer): ${SECONDS} s"
    "$python3" "$here/check_box_faults.py" "$out" "$dbc" "$work/sent.json"
    ;;
  display|box-view)
    # scopekin display --can vcan0 beside the box: 4 s of traffic; the page's scripts (argument 14)
    # go to the guest, as the view's build folder is not there.
    assets=${14}
    "$python3" "$here/make_handle_log.py" "$dbc" "$work/handle.log" --duration 4 --gap 0 > "$work/sent.json"
    # Without its debug sections (the sanitizer build's is ~200 MB: more than the initramfs holds).
    strip --strip-debug -o "$work/scopekin" "$scopekin"
    bash "$here/vm_run.sh" "${common[@]}" --memory 1024 --script "$here/display_on_vcan.sh" \
      --bin "$canplayer" --bin "$work/scopekin:scopekin" --file "$work/handle.log:/scopekin/handle.log" \
      --file "$assets:/scopekin/assets" -- "$scenario"
    echo "VM run (boot, 4 s of traffic, the display read, file transfer): ${SECONDS} s"
    "$python3" "$here/check_display_run.py" "$out" 4 "$scenario"
    ;;
  *)
    echo "run_box_vm_test.sh: unknown scenario '$scenario' (traffic, faults, display or box-view)" >&2
    exit 2
    ;;
esac
