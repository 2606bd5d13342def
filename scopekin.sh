#!/usr/bin/env bash
# scopekin — single entry point for building, running and testing.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$ROOT"

# Debian 12 packages.  The main job needs only the compiler, CMake and the host libraries of the
# `scopekin` program, plus matplotlib for its plots; the tests need the rest (GoogleTest, Google
# Benchmark, the cross toolchains, the emulators, clang for the fuzzers, the VM test's tools).
MAIN_PACKAGES=(
  cmake ninja-build g++ ccache
  libeigen3-dev libcli11-dev nlohmann-json3-dev
  python3 python3-matplotlib
  libcpp-httplib-dev pkg-config
)
TEST_PACKAGES=(
  "${MAIN_PACKAGES[@]}"
  libgtest-dev libgmock-dev googletest libbenchmark-dev
  g++-aarch64-linux-gnu libc6-dev-arm64-cross
  gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib
  qemu-user qemu-system-arm
  python3-canmatrix python3-sklearn
  clang-14 libclang-rt-14-dev clang-format-14
  qemu-system-x86 busybox-static can-utils cpio xz-utils iproute2
  chromium
)
ALL_PRESETS=(host asan aarch64 cortex-m4 fuzz)
BUILD_JOBS=2
MAIN_START=$SECONDS

usage() {
  cat <<USAGE
Usage: ./scopekin.sh <command> [args]

Commands:
  main [args...]      Install the missing Debian packages the main job needs, configure the 'app'
                      preset (no tests) and build only the 'scopekin' program (and the reduced
                      tables it is built with), then run the main job, a simulated colonoscopy
                      through the firmware:
                        build/app/host_sim/scopekin demo --out build/demo [args...]
                      (args go to 'scopekin demo'; an --out of your own replaces build/demo).
                      One progress line per stage: packages, configure, build, demo.
  test [preset...]    Install the missing Debian packages the tests need, then for each preset
                      (default: all of ${ALL_PRESETS[*]}) configure, build (-j${BUILD_JOBS}) and
                      run ctest.  Ends with one CTest-style line summed over all presets, e.g.
                        100% tests passed, 0 tests failed out of N
                      A preset that fails to configure or build counts as one failed test.
                      Exit status is non-zero if anything failed.
  test --quick        The edit-test loop: the 'host' preset, built, and its tests but the SocketCAN
                      VM and the discrepancy checks (test preset 'host-quick'); same summary line.
  -h, --help, help    Show this help.

Builds go through ccache (cache in ~/.cache/ccache, 8 GB at most), so a second build of the same
sources, in this clone or another, recompiles only what changed; SCOPEKIN_NO_CCACHE=1 turns it off.
Packages are checked with dpkg-query; only if some are missing does the script run
'apt-get update' and 'apt-get install -y --no-install-recommends <missing>' (as root, or via sudo).
Logs of 'test' are kept in build/logs/<preset>.log; the last 25 lines of each failed test's
output are printed again just before the summary (and kept in build/logs/failed_tails.log).
USAGE
}

# ensure_packages <package>...: installs those that are missing.
ensure_packages() {
  local missing=() pkg
  for pkg in "$@"; do
    if [[ "$(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null || true)" != "installed" ]]; then
      missing+=("$pkg")
    fi
  done
  if [[ ${#missing[@]} -eq 0 ]]; then
    return 0
  fi
  echo "scopekin.sh: installing missing packages: ${missing[*]}"
  local sudo=()
  if [[ $EUID -ne 0 ]]; then
    sudo=(sudo)
  fi
  "${sudo[@]}" apt-get update
  "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y --no-install-recommends "${missing[@]}"
}

# ensure_node: Node.js (>= 18) and npm, which bundle the browser view's page at build time
# (host_sim/view/web: npm ci from the npm registry, then esbuild).  A machine that already has
# both (from Debian or elsewhere) keeps them; otherwise Debian's nodejs and npm are installed.
ensure_node() {
  if command -v node >/dev/null && command -v npm >/dev/null &&
     node -e 'process.exit(Number(process.versions.node.split(".")[0]) >= 18 ? 0 : 1)'; then
    return 0
  fi
  ensure_packages nodejs npm
}

# use_compiler_cache: compile through ccache, so that a second build of the same sources (another
# clone, a CI run after a small change) recompiles only what changed.  Paths are hashed relative to
# the checkout (CCACHE_BASEDIR, CCACHE_NOHASHDIR), so clones in other folders share the cache; a
# -D that holds an absolute path (the CLI's data files) still keys its objects to their clone.
# The cache lives in ~/.cache/ccache (ccache's default), capped at 8 GB.  SCOPEKIN_NO_CCACHE=1
# builds without it, e.g. to time a cold build.
use_compiler_cache() {
  if [[ "${SCOPEKIN_NO_CCACHE:-0}" == 1 ]] || ! command -v ccache >/dev/null; then
    return 0
  fi
  export CMAKE_C_COMPILER_LAUNCHER=ccache CMAKE_CXX_COMPILER_LAUNCHER=ccache
  export CCACHE_BASEDIR="$ROOT" CCACHE_NOHASHDIR=true CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-8G}"
}

# stage <n> <of> <text>: one progress line, with the seconds since the command started.
stage() {
  echo "scopekin.sh main [$1/$2] $3 (at $((SECONDS - MAIN_START)) s)"
}

cmd_main() {
  stage 1 4 "packages: ${MAIN_PACKAGES[*]}"
  ensure_packages "${MAIN_PACKAGES[@]}"
  ensure_node
  use_compiler_cache
  stage 2 4 "configure: cmake --preset app"
  cmake --preset app --log-level=WARNING
  stage 3 4 "build: cmake --build --preset app (the scopekin program and what it needs)"
  cmake --build --preset app -j "$BUILD_JOBS"
  local cli=build/app/host_sim/scopekin
  if [[ ! -x "$cli" ]]; then
    echo "scopekin.sh: $cli was not built" >&2
    exit 1
  fi
  local out=(--out build/demo) arg
  for arg in "$@"; do
    if [[ "$arg" == --out || "$arg" == --out=* ]]; then
      out=()
    fi
  done
  stage 4 4 "demo: $cli demo ${out[*]} $*"
  exec "$cli" demo "${out[@]}" "$@"
}

cmd_test() {
  if [[ "${1:-}" == --quick ]]; then
    if [[ $# -ne 1 ]]; then
      echo "scopekin.sh: test --quick takes no presets (it is the host preset's quick tests)" >&2
      exit 2
    fi
    run_presets quick
    return
  fi
  local presets=("$@")
  if [[ ${#presets[@]} -eq 0 ]]; then
    presets=("${ALL_PRESETS[@]}")
  fi
  local p k known
  for p in "${presets[@]}"; do
    known=0
    for k in "${ALL_PRESETS[@]}"; do [[ "$p" == "$k" ]] && known=1; done
    if [[ $known -eq 0 ]]; then
      echo "scopekin.sh: unknown preset '$p' (known: ${ALL_PRESETS[*]})" >&2
      exit 2
    fi
  done

  run_presets "${presets[@]}"
}

# run_presets <preset>...: configure, build and test each; "quick" is the host preset with the
# host-quick test preset.  Prints the summary; fails if anything failed.
run_presets() {
  ensure_packages "${TEST_PACKAGES[@]}"
  ensure_node
  use_compiler_cache
  mkdir -p build/logs
  rm -f build/logs/failed_tails.log

  local total=0 failed=0 broken=() report=() start seconds log line t f p configure test_preset
  for p in "$@"; do
    configure=$p
    test_preset=$p
    if [[ $p == quick ]]; then
      configure=host
      test_preset=host-quick
    fi
    echo "==================== preset: $p ===================="
    start=$SECONDS
    log="build/logs/$p.log"
    if ! cmake --preset "$configure"; then
      broken+=("$p (configure)"); failed=$((failed + 1)); total=$((total + 1))
      report+=("$p: configure FAILED"); continue
    fi
    if ! cmake --build --preset "$configure" -j "$BUILD_JOBS"; then
      broken+=("$p (build)"); failed=$((failed + 1)); total=$((total + 1))
      report+=("$p: build FAILED"); continue
    fi
    set +e
    ctest --preset "$test_preset" 2>&1 | tee "$log"
    local rc=${PIPESTATUS[0]}
    set -e
    seconds=$((SECONDS - start))
    line="$(grep -E '^[0-9]+% tests passed, [0-9]+ tests failed out of [0-9]+' "$log" | tail -n 1 || true)"
    if [[ -n "$line" ]]; then
      f="$(sed -E 's/^[0-9]+% tests passed, ([0-9]+) tests failed out of ([0-9]+).*/\1/' <<<"$line")"
      t="$(sed -E 's/^[0-9]+% tests passed, ([0-9]+) tests failed out of ([0-9]+).*/\2/' <<<"$line")"
      if [[ $rc -ne 0 && $f -eq 0 ]]; then
        f=1  # ctest failed for another reason; never report it as a pass
      fi
    else
      t=1; f=1  # no tests found or ctest did not get to run them
    fi
    total=$((total + t)); failed=$((failed + f))
    if [[ $f -ne 0 ]]; then
      broken+=("$p (tests)")
      failed_tests_tail "build/$configure/Testing/Temporary/LastTest.log" >>build/logs/failed_tails.log
    fi
    report+=("$p: $((t - f))/$t passed, ${seconds}s configure+build+test")
  done

  # The end of each failed test's output again, next to the summary (a CI log is often read from
  # its end, and the host preset's output runs to thousands of lines).
  if [[ -s build/logs/failed_tails.log ]]; then
    cat build/logs/failed_tails.log
  fi
  echo "==================== summary ===================="
  local r
  for r in "${report[@]}"; do echo "  $r"; done
  if [[ ${#broken[@]} -gt 0 ]]; then
    echo "  failed: ${broken[*]}"
  fi
  # CTest's own formula: rounded percentage, never 100% while something failed.
  local percent=0
  if [[ $total -gt 0 ]]; then
    percent=$(( ((total - failed) * 200 + total) / (2 * total) ))
    if [[ $failed -gt 0 && $percent -gt 99 ]]; then
      percent=99
    fi
  fi
  echo "${percent}% tests passed, ${failed} tests failed out of ${total}"
  [[ $failed -eq 0 && $total -gt 0 ]]
}

# The last 25 lines of the output of every failed test in a CTest LastTest.log.
failed_tests_tail() {
  [[ -f $1 ]] || return 0
  awk '
    / Testing: / { name = $3; n = 0; inside = 0; next }
    /^Output:$/ { inside = 1; getline; next }
    /^<end of output>$/ { inside = 0; next }
    inside { lines[n++] = $0; next }
    /^Test Failed\.$/ || /^Test Failed / {
      print "==================== failed: " name " (its last lines) ===================="
      for (i = (n > 25 ? n - 25 : 0); i < n; i++) print "  " lines[i]
    }' "$1"
}

main() {
  if [[ $# -eq 0 ]]; then
    usage >&2
    exit 2
  fi
  local command=$1
  shift
  case "$command" in
    main) cmd_main "$@" ;;
    test) cmd_test "$@" ;;
    -h|--help|help) usage ;;
    *)
      echo "scopekin.sh: unknown command '$command'" >&2
      usage >&2
      exit 2
      ;;
  esac
}

main "$@"
