#!/usr/bin/env bash
# run_fuzzer.sh — runs one libFuzzer target for a bounded time on a fresh COPY of its seed corpus
# (the source tree is never written), prints the executions, and appends "<name> <executions>"
# to the executions file (summed by `fuzz.summary`, recorded in hal/README.md).
#
# Usage: run_fuzzer.sh <name> <fuzzer> <work dir> <seconds> <executions file> <dictionary> <seed dir>...
#        (<dictionary>: a libFuzzer -dict= file, or "-" for none)
#        run_fuzzer.sh --summary <executions file>     (per target and total; fails if empty)
#
# Exit status: libFuzzer's — non-zero on a crash, a sanitizer report (ASan, UBSan with
# -fno-sanitize-recover), a timeout (-timeout, per input), a leak or an out-of-memory
# (-rss_limit_mb); the failing input is kept as <work dir>/crash-*, timeout-*, leak-* or oom-*.
set -u -o pipefail

if [[ ${1:-} == --summary ]]; then
  if [[ ! -s ${2:-} ]]; then
    echo "fuzz summary: no executions recorded in ${2:-<none>}" >&2
    exit 1
  fi
  awk '{ total += $2; print "fuzz executions: " $1 " " $2 }
       END { print "fuzz executions: total " total }' "$2"
  exit 0
fi

if [[ $# -lt 7 ]]; then
  echo "usage: $0 <name> <fuzzer> <work dir> <seconds> <executions file> <dictionary|-> <seed dir>..." >&2
  exit 2
fi
name=$1 fuzzer=$2 work=$3 seconds=$4 executions_file=$5 dictionary=$6
shift 6
dict_option=()
if [[ $dictionary != - ]]; then
  if [[ ! -f $dictionary ]]; then
    echo "fuzz $name: no dictionary $dictionary" >&2
    exit 2
  fi
  dict_option=(-dict="$dictionary")
fi

rm -rf "$work"
mkdir -p "$work/corpus"
for seeds in "$@"; do
  if [[ -d "$seeds" ]]; then
    cp -- "$seeds"/* "$work/corpus/" 2>/dev/null || true
  fi
done
echo "fuzz $name: $(find "$work/corpus" -type f | wc -l) seed inputs, ${seconds} s, dictionary ${dictionary}"

"$fuzzer" \
  "${dict_option[@]}" \
  -max_total_time="$seconds" \
  -timeout=5 \
  -rss_limit_mb=2048 \
  -print_final_stats=1 \
  -artifact_prefix="$work/" \
  "$work/corpus" 2>&1 | tee "$work/fuzzer.log"
status=${PIPESTATUS[0]}

executions=$(sed -n 's/^stat::number_of_executed_units: *\([0-9][0-9]*\).*/\1/p' "$work/fuzzer.log" | tail -n 1)
executions=${executions:-0}
echo "fuzz $name: $executions executions, exit status $status"
mkdir -p "$(dirname "$executions_file")"
echo "$name $executions" >> "$executions_file"
if [[ $status -ne 0 ]]; then
  echo "fuzz $name: FAILED — the input is in $work/ (crash-*, timeout-*, leak-*, oom-*)" >&2
fi
exit "$status"
