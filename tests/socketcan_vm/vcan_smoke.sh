# vcan_smoke.sh — guest script (busybox sh) for the socketcan_vm_smoke test; run by vm_run.sh with
#   --bin cansend --bin candump --file guest_lib.sh:/scopekin/guest_lib.sh
# Checks, on vcan0 in the VM:
#   1. a data frame sent with cansend is received by candump (-L log format);
#   2. an error frame injected from user space (cansend 20000040#..., i.e. CAN_ERR_FLAG|CAN_ERR_BUSOFF)
#      reaches a CAN_RAW socket whose CAN_RAW_ERR_FILTER covers it (candump IF,0~0,#FFFFFFFF: no
#      data frames, all error classes), and does NOT reach a socket with the default filters.
# The candump logs are written to /out (→ --out DIR on the host).
set -u

failures=0
pass() { echo "PASS: $*"; }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

. /scopekin/guest_lib.sh   # wait_receivers

ip link show vcan0 | grep -q 'UP' || fail "vcan0 is not up"

# --- 1. data frame round trip --------------------------------------------------------------------
candump -L -n 1 -T 10000 vcan0 > /out/candump_data.log 2>&1 &
dump=$!
wait_receivers rcvlist_all 1
cansend vcan0 123#DEADBEEF || fail "cansend vcan0 123#DEADBEEF (status $?)"
wait $dump
cat /out/candump_data.log
if grep -q '^([0-9]*\.[0-9]*) vcan0 123#DEADBEEF$' /out/candump_data.log; then
  pass "data frame 123#DEADBEEF sent by cansend received by candump"
else
  fail "candump did not log 123#DEADBEEF"
fi

# --- 2. error frame injected from user space -----------------------------------------------------
# Receivers: errors only (0~0 matches no data frame, #FFFFFFFF = CAN_ERR_MASK), and default filters.
candump -L -n 1 -T 10000 'vcan0,0~0,#FFFFFFFF' > /out/candump_err.log 2>&1 &
err_dump=$!
candump -L -T 1500 vcan0 > /out/candump_plain.log 2>&1 &
plain_dump=$!
wait_receivers rcvlist_err 1
wait_receivers rcvlist_all 1
# An 8-digit id with bit 29 set: can-utils' parse_canframe keeps CAN_ERR_FLAG (no CAN_EFF_FLAG).
cansend vcan0 20000040#0000000000000000 || fail "cansend of the error frame (status $?)"
# ... then a data frame, which proves that the default-filter candump was listening.
cansend vcan0 124#01 || fail "cansend vcan0 124#01 (status $?)"
wait $err_dump
wait $plain_dump
cat /out/candump_err.log
if grep -q '^([0-9]*\.[0-9]*) vcan0 20000040#0000000000000000$' /out/candump_err.log; then
  pass "error frame CAN_ERR_FLAG|CAN_ERR_BUSOFF injected by cansend received with CAN_RAW_ERR_FILTER"
else
  fail "error frame not received by candump with error filter #FFFFFFFF"
fi
cat /out/candump_plain.log
if ! grep -q ' vcan0 124#01$' /out/candump_plain.log; then
  fail "the default-filter candump missed data frame 124#01"
elif grep -q '20000040' /out/candump_plain.log; then
  fail "error frame received by a socket without CAN_RAW_ERR_FILTER"
else
  pass "error frame not delivered to a socket with default filters (which got 124#01)"
fi

echo "vcan_smoke: $failures failure(s)"
[ $failures -eq 0 ]
