#!/usr/bin/env bash
# run_box_vm_test.sh — the test socketcan_vm.scopekin_box, host side:
#   1. make_handle_log.py writes the handle sensors' 1 kHz traffic (10 s) from the DBC;
#   2. vm_run.sh boots the kernel, and box_on_vcan.sh runs scopekin-box on vcan0 while canplayer
#      replays the traffic and candump records the bus;
#   3. check_box_run.py checks the box's statistics and every frame it sent (decoded with the DBC);
#   4. `scopekin replay` runs the box's own candump record (--record) through the firmware on the
#      host and must give back, frame for frame, the outputs the box sent in the VM.
# usage: run_box_vm_test.sh PYTHON3 DBC OUT_DIR CACHE VM_TIMEOUT_S SCOPEKIN_BOX CANPLAYER CANDUMP CANSEND SCOPEKIN
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
python3=$1 dbc=$2 out=$3 cache=$4 vm_timeout=$5 box=$6 canplayer=$7 candump=$8 cansend=$9 scopekin=${10}
mkdir -p "$out"
work="$out.work"
rm -rf "$work" && mkdir -p "$work"
"$python3" "$here/make_handle_log.py" "$dbc" "$work/handle_1khz.log" > "$work/sent.json"
echo "input: $(cat "$work/sent.json")"
SECONDS=0
bash "$here/vm_run.sh" --cache "$cache" --script "$here/box_on_vcan.sh" --out "$out" --clean-out \
  --timeout "$vm_timeout" --quiet \
  --bin "$box:scopekin-box" --bin "$canplayer" --bin "$candump" --bin "$cansend" \
  --file "$work/handle_1khz.log:/scopekin/handle_1khz.log" \
  --file "$here/guest_lib.sh:/scopekin/guest_lib.sh"
echo "VM run (boot, 10 s of traffic, file transfer): ${SECONDS} s"
"$python3" "$here/check_box_run.py" "$out" "$dbc" "$work/sent.json"
gunzip -c "$out/box_record.log.gz" > "$work/box_record.log"
"$scopekin" replay "$work/box_record.log" --out "$work/replay" --quiet
"$python3" -c 'import json,sys; s=json.load(open(sys.argv[1])); print("replay of the box record: %d periods, %d output frames compared, %d differ" % (s["periods"], s["compared_frames"], s["differing_frames"])); sys.exit(0 if s["identical"] else 1)' "$work/replay/summary.json"
