#!/usr/bin/env bash
# vm_run.sh — run a shell script (plus host programs) inside Debian's stock kernel with SocketCAN
# (vcan) under qemu-system-x86_64.  See tests/socketcan_vm/README.md and --help.
set -euo pipefail

readonly PROG=${0##*/}
readonly DEFAULT_MODULES=(can can-raw can-dev vcan)

usage() {
  cat <<EOF
Usage: $PROG --cache DIR --script GUEST_SCRIPT [options] [-- SCRIPT_ARGS...]

Boot Debian's stock x86-64 kernel (package linux-image-amd64) in qemu-system-x86_64 with a busybox
initramfs, load the SocketCAN modules, create and bring up vcan0, run GUEST_SCRIPT with /bin/sh
(busybox ash) in the guest, power off.  The exit status is the guest script's exit status.

Required:
  --cache DIR            Kernel cache: the .deb (apt-get download) and the extracted vmlinuz and
                         modules live here and are reused between runs.
  --script FILE          Host file run in the guest as: /bin/sh /scopekin/script.sh SCRIPT_ARGS...
                         (working directory /tmp, a tmpfs).

Options:
  --bin HOSTPATH[:NAME]  Copy a host executable into the guest as /bin/NAME (default NAME: its file
                         name; a NAME starting with / is a full guest path), together with every
                         shared library ldd reports and the dynamic loader, at the host paths.
                         Repeatable.
  --file HOSTPATH:GUESTPATH
                         Copy a host file (or directory, recursively) to an absolute guest path.
                         Repeatable.
  --out DIR              Host directory that receives what the guest script writes under /out
                         (sent back as a base64 tar on the guest's second serial port), plus
                         console.log (the guest console) and vm_run.log (timings).
  --clean-out            Empty the --out DIR first; only done if DIR is empty or was used by
                         vm_run.sh before (it holds the marker file .vm_run_out).
  --timeout SECONDS      Kill QEMU after this long (default 120; the kernel download/extraction on
                         a cold cache is not counted).
  --module NAME          Also load this kernel module (and its dependencies), e.g. can-bcm,
                         can-gw, can-isotp, vxcan.  Repeatable.  Always loaded: ${DEFAULT_MODULES[*]}.
  --vcan-count N         Create vcan0 .. vcan<N-1> (default 1; 0 creates none).
  --accel tcg|kvm        QEMU accelerator (default tcg, or \$SCOPEKIN_VM_ACCEL).
  --memory MB            Guest RAM (default 512).
  --quiet                Do not stream the console; print its last lines only on failure.
  -h, --help             This text.

Environment:
  SCOPEKIN_VM_KERNEL_PKG  Use this kernel package (e.g. linux-image-6.1.0-56-amd64) instead of the
                          one linux-image-amd64 depends on.
  SCOPEKIN_VM_BUSYBOX     busybox binary to use (default /bin/busybox from busybox-static).
  SCOPEKIN_VM_ACCEL       Default for --accel.
  SCOPEKIN_VM_BZIMAGE     If set, boot the compressed bzImage instead of the PVH ELF vmlinux.
  SCOPEKIN_VM_KEEP        If set, keep the temporary work directory (initramfs tree, initrd.cpio,
                          raw console and second-serial-port captures) and print its path.

Guest environment: PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin, busybox applets, the CAN modules loaded
(copies in /lib/modules/<kver>/<name>.ko, e.g. to re-insmod vcan with echo=1), vcan0 up, lo up,
/proc /sys /dev /tmp mounted, /out empty, SCOPEKIN_VM=1, LD_LIBRARY_PATH covering the copied
libraries.

Exit status: the guest script's status, or
  124  the VM did not finish within --timeout;
  125  harness failure (kernel fetch, boot, module load, vcan setup, missing exit marker, /out
       transfer);
    2  usage error.
EOF
}

die()     { printf '%s: error: %s\n' "$PROG" "$*" >&2; exit 125; }
usage_die() { printf '%s: %s (see --help)\n' "$PROG" "$*" >&2; exit 2; }
note()    { printf '%s: %s\n' "$PROG" "$*" >&2; }

# ------------------------------------------------------------------------------------------------
# Arguments
# ------------------------------------------------------------------------------------------------
cache=''
script=''
out=''
timeout_s=120
accel=${SCOPEKIN_VM_ACCEL:-tcg}
memory=512
quiet=0
clean_out=0
vcan_count=1
bins=()
files=()
modules=("${DEFAULT_MODULES[@]}")
script_args=()

need_arg() { [[ $# -ge 2 ]] || usage_die "$1 needs an argument"; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --cache)      need_arg "$@"; cache=$2; shift 2 ;;
    --script)     need_arg "$@"; script=$2; shift 2 ;;
    --bin)        need_arg "$@"; bins+=("$2"); shift 2 ;;
    --file)       need_arg "$@"; files+=("$2"); shift 2 ;;
    --out)        need_arg "$@"; out=$2; shift 2 ;;
    --timeout)    need_arg "$@"; timeout_s=$2; shift 2 ;;
    --module)     need_arg "$@"; modules+=("$2"); shift 2 ;;
    --vcan-count) need_arg "$@"; vcan_count=$2; shift 2 ;;
    --accel)      need_arg "$@"; accel=$2; shift 2 ;;
    --memory)     need_arg "$@"; memory=$2; shift 2 ;;
    --quiet)      quiet=1; shift ;;
    --clean-out)  clean_out=1; shift ;;
    -h|--help)    usage; exit 0 ;;
    --)           shift; script_args=("$@"); break ;;
    *)            usage_die "unknown argument '$1'" ;;
  esac
done

[[ -n $cache ]]  || usage_die "--cache DIR is required"
[[ -n $script ]] || usage_die "--script FILE is required"
[[ -f $script ]] || usage_die "guest script '$script' not found"
[[ $timeout_s =~ ^[1-9][0-9]*$ ]]  || usage_die "--timeout must be a positive integer"
[[ $vcan_count =~ ^[0-9]+$ ]]      || usage_die "--vcan-count must be a non-negative integer"
[[ $memory =~ ^[1-9][0-9]*$ ]]     || usage_die "--memory must be a positive integer"
case $accel in tcg|kvm) ;; *) usage_die "--accel must be tcg or kvm" ;; esac

for tool in qemu-system-x86_64 cpio base64 tar timeout flock ldd; do
  command -v "$tool" >/dev/null 2>&1 || die "'$tool' not found (Debian packages: qemu-system-x86 cpio coreutils tar util-linux libc-bin)"
done
busybox=${SCOPEKIN_VM_BUSYBOX:-/bin/busybox}
[[ -x $busybox ]] || die "busybox not found at $busybox (install Debian package busybox-static)"

mkdir -p "$cache"
cache=$(cd "$cache" && pwd)
[[ $clean_out == 0 || -n $out ]] || usage_die "--clean-out needs --out DIR"
if [[ -n $out ]]; then
  mkdir -p "$out"; out=$(cd "$out" && pwd)
  if [[ $clean_out == 1 ]]; then
    if [[ -e $out/.vm_run_out || -z $(ls -A "$out") ]]; then
      find "$out" -mindepth 1 -delete
    else
      die "--clean-out: refusing to empty $out (not a vm_run.sh output directory: no .vm_run_out)"
    fi
  fi
  : > "$out/.vm_run_out"
fi

work=$(mktemp -d "${TMPDIR:-/tmp}/scopekin-vm.XXXXXX")
qemu_pid_file=$work/qemu.pid
cleanup() {
  if [[ -s $qemu_pid_file ]]; then kill "$(cat "$qemu_pid_file")" 2>/dev/null || true; fi
  if [[ -n ${SCOPEKIN_VM_KEEP:-} ]]; then note "keeping $work (SCOPEKIN_VM_KEEP)"; else rm -rf "$work"; fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

norm() { local n=${1%%.ko*}; n=${n##*/}; printf '%s' "${n//-/_}"; }   # module name → can_raw form

# ------------------------------------------------------------------------------------------------
# Kernel: resolve, download (apt-get download), extract vmlinuz and the modules (cached)
# Cache layout:
#   DIR/debs/<pkg>_<ver>_amd64.deb
#   DIR/kernel-v1/<pkg>_<ver>/{vmlinuz,vmlinux,kver,modules.idx,modules/<name>.ko,.complete}
# vmlinux is the bzImage payload decompressed on the host (only when the kernel has CONFIG_PVH):
# QEMU boots such an ELF through its PVH entry point, which skips the ~2.5 s that the XZ
# decompressor needs under TCG.
# modules.idx lists every module of the package: "<name> <path in deb> <dep,dep,...>".
# ------------------------------------------------------------------------------------------------
resolve_kernel_pkg() {   # prints "<pkg> <version>" or nothing
  local pkg=${SCOPEKIN_VM_KERNEL_PKG:-} line
  if [[ -n $pkg ]]; then
    line=$(apt-cache show --no-all-versions "$pkg" 2>/dev/null | awk '$1 == "Version:" { print $2; exit }') || true
    [[ -n $line ]] && printf '%s %s\n' "$pkg" "$line"
    return 0
  fi
  # The candidate linux-image-amd64 depends on exactly one "linux-image-<abi>-amd64 (= <version>)".
  # apt-cache takes ~0.7 s, so the answer is memoised against the state of the package lists.
  local sig lists=/var/lib/apt/lists memo=$cache/resolved-kernel
  eval "$(apt-config shell lists Dir::State::lists/d 2>/dev/null)" || true
  sig=$(stat -c '%n %Y %s' "${lists%/}"/*_Packages* 2>/dev/null | cksum | tr ' ' -) || true
  if [[ -f $memo && $(head -n 1 "$memo") == "$sig" ]]; then
    sed -n 2p "$memo"
    return 0
  fi
  line=$(apt-cache show --no-all-versions linux-image-amd64 2>/dev/null \
    | awk '$1 == "Depends:" { if (match($0, /linux-image-[0-9][^ ,]*-amd64 \(= [^)]+\)/)) {
             split(substr($0, RSTART, RLENGTH), a, /[ ()=]+/); print a[1], a[2]; exit } }') || true
  if [[ -n $line ]]; then
    printf '%s\n%s\n' "$sig" "$line" > "$memo.$$" && mv "$memo.$$" "$memo"
    printf '%s\n' "$line"
  fi
  return 0
}

decompress_ko() {   # $1 = source .ko[.xz|.zst|.gz], $2 = destination .ko
  case $1 in
    *.ko)     cp "$1" "$2" ;;
    *.ko.xz)  xz -dc "$1" > "$2" ;;
    *.ko.zst) zstd -q -dc "$1" > "$2" ;;
    *.ko.gz)  gzip -dc "$1" > "$2" ;;
    *) die "unknown module format: $1" ;;
  esac
}

# extract_vmlinux BZIMAGE OUT: decompress the bzImage payload (boot protocol >= 2.08 header fields
# payload_offset at 0x248 and payload_length at 0x24c, relative to the protected-mode code).
extract_vmlinux() {
  local bz=$1 dst=$2 setup_sects off len magic
  u32() { od -An -t u4 -j "$1" -N 4 "$bz" | tr -d ' '; }
  [[ $(od -An -c -j 514 -N 4 "$bz" | tr -d ' ') == HdrS ]] || return 1
  setup_sects=$(od -An -t u1 -j 497 -N 1 "$bz" | tr -d ' ')
  [[ $setup_sects == 0 ]] && setup_sects=4
  off=$(( (setup_sects + 1) * 512 + $(u32 584) ))
  len=$(u32 588)
  [[ $len -gt 0 ]] || return 1
  magic=$(od -An -t x1 -j "$off" -N 4 "$bz" | tr -d ' ')
  case $magic in
    fd377a58) tail -c "+$((off + 1))" "$bz" | head -c "$len" | xz -dc --single-stream > "$dst" 2>/dev/null || true ;;
    1f8b*)    tail -c "+$((off + 1))" "$bz" | head -c "$len" | gzip -dc > "$dst" 2>/dev/null || true ;;
    28b52ffd) tail -c "+$((off + 1))" "$bz" | head -c "$len" | zstd -q -dc > "$dst" 2>/dev/null || true ;;
    *) return 1 ;;
  esac
  # Accept only a complete ELF file: the section header table lies at its end (e_shoff + size).
  if [[ $(od -An -t x1 -N 4 "$dst" 2>/dev/null | tr -d ' ') == 7f454c46 ]]; then
    local shoff shnum shentsize size
    shoff=$(od -An -t u8 -j 40 -N 8 "$dst" | tr -d ' ')
    shentsize=$(od -An -t u2 -j 58 -N 2 "$dst" | tr -d ' ')
    shnum=$(od -An -t u2 -j 60 -N 2 "$dst" | tr -d ' ')
    size=$(stat -c %s "$dst")
    [[ $size -ge $(( shoff + shnum * shentsize )) ]] && return 0
  fi
  rm -f "$dst"
  return 1
}

ensure_kernel() {
  local pkg ver key kdir deb tmp
  read -r pkg ver < <(resolve_kernel_pkg) || true
  if [[ -z ${pkg:-} ]]; then
    # Offline / empty package lists: fall back to the newest kernel already in the cache.
    kdir=$(ls -d "$cache"/kernel-v1/*/ 2>/dev/null | sort -V | while read -r d; do
             [[ -f $d/.complete ]] && printf '%s\n' "${d%/}"; done | tail -n 1) || true
    if [[ -z $kdir ]]; then
      die "cannot resolve the kernel package: 'apt-cache show linux-image-amd64' found nothing.
  The APT package lists are probably empty (fresh container).  Run 'apt-get update' (as root)
  once, then retry.  (Or set SCOPEKIN_VM_KERNEL_PKG=linux-image-<abi>-amd64.)"
    fi
    note "apt cannot resolve linux-image-amd64; using cached kernel $(basename "$kdir")"
    kernel_dir=$kdir
    return
  fi
  key=${pkg}_${ver}
  kdir=$cache/kernel-v1/$key
  kernel_dir=$kdir
  [[ -f $kdir/.complete ]] && return

  mkdir -p "$cache/debs"
  deb=$(ls "$cache/debs/${pkg}_${ver//:/%3a}_"*.deb 2>/dev/null | head -n 1) || true
  if [[ -z $deb ]]; then
    note "downloading $pkg=$ver into $cache/debs (once)"
    # apt-get download works unprivileged; as root it warns that _apt cannot write here — harmless.
    if ! (cd "$cache/debs" && apt-get download -q "$pkg=$ver") >"$work/apt.log" 2>&1; then
      cat "$work/apt.log" >&2
      die "'apt-get download $pkg=$ver' failed.  If the package lists are empty or stale, run
  'apt-get update' (as root) and retry; this script never runs it itself."
    fi
    deb=$(ls "$cache/debs/${pkg}_${ver//:/%3a}_"*.deb 2>/dev/null | head -n 1) || true
    [[ -n $deb ]] || die "apt-get download succeeded but no ${pkg}_*.deb in $cache/debs"
  fi

  note "extracting vmlinuz and the module index from $(basename "$deb")"
  tmp=$cache/kernel-v1/.tmp.$$
  rm -rf "$tmp"; mkdir -p "$tmp/x"
  dpkg-deb -x "$deb" "$tmp/x"
  local vmlinuz moddir kver
  vmlinuz=$(ls "$tmp"/x/boot/vmlinuz-* 2>/dev/null | head -n 1) || true
  [[ -n $vmlinuz ]] || die "no boot/vmlinuz-* in $deb"
  moddir=$(ls -d "$tmp"/x/lib/modules/*/ "$tmp"/x/usr/lib/modules/*/ 2>/dev/null | head -n 1) || true
  [[ -n $moddir ]] || die "no lib/modules/<kver>/ in $deb"
  moddir=${moddir%/}
  kver=${moddir##*/}
  mkdir -p "$tmp/k/modules"
  cp "$vmlinuz" "$tmp/k/vmlinuz"
  if grep -q '^CONFIG_PVH=y' "$tmp"/x/boot/config-* 2>/dev/null; then
    extract_vmlinux "$vmlinuz" "$tmp/k/vmlinux" || note "cannot extract an ELF vmlinux (booting the bzImage; slower)"
  fi
  printf '%s\n' "$kver" > "$tmp/k/kver"
  # Index: the deb has no modules.dep (depmod runs in postinst), so read depends= from .modinfo
  # (NUL-separated strings; grep -z reads them as records).
  (cd "$moddir" && find kernel -name '*.ko*' -print0 | sort -z |
     while IFS= read -r -d '' f; do
       case $f in
         *.ko)     printf '%s\0' "$f" >&3 ;;   # batched below
         *.ko.xz)  printf '%s %s\n' "$f" "$(xz -dc "$f" | grep -a -z -m1 '^depends=' | tr -d '\0')" ;;
         *.ko.zst) printf '%s %s\n' "$f" "$(zstd -q -dc "$f" | grep -a -z -m1 '^depends=' | tr -d '\0')" ;;
         *.ko.gz)  printf '%s %s\n' "$f" "$(gzip -dc "$f" | grep -a -z -m1 '^depends=' | tr -d '\0')" ;;
       esac
     done 3>"$tmp/plain.list") > "$tmp/deps.txt"
  if [[ -s $tmp/plain.list ]]; then
    (cd "$moddir" && xargs -0 grep -a -z -H '^depends=' < "$tmp/plain.list" | tr '\0' '\n' \
       | sed 's/:depends=/ depends=/') >> "$tmp/deps.txt"
  fi
  # → "<name> <path> <dep,dep|->", name normalised like can-raw → can_raw
  awk '{ d = $2; sub(/^depends=/, "", d); if (d == "") d = "-"
         n = $1; sub(/.*\//, "", n); sub(/\.ko.*$/, "", n); gsub(/-/, "_", n)
         print n, $1, d }' "$tmp/deps.txt" | sort > "$tmp/k/modules.idx"
  # Keep the package's modules under net/can and drivers/net/can (+ dependencies) in the cache.
  local m want=()
  while read -r m _; do want+=("$m"); done < <(grep -E ' kernel/(net|drivers/net)/can/' "$tmp/k/modules.idx")
  copy_modules "$tmp/k" "$moddir" "${want[@]}"
  : > "$tmp/k/.complete"
  rm -rf "$kdir"; mkdir -p "$(dirname "$kdir")"
  mv "$tmp/k" "$kdir"
  rm -rf "$tmp"
}

# closure KDIR NAME... → sets CLOSURE to the module names in load order (dependencies first)
closure() {
  local kdir=$1; shift
  local -A seen=()
  CLOSURE=()
  local x
  _visit() {
    local n; n=$(norm "$1")
    [[ -n ${seen[$n]:-} ]] && return 0
    seen[$n]=1
    local line; line=$(awk -v n="$n" '$1 == n { print; exit }' "$kdir/modules.idx")
    [[ -n $line ]] || die "kernel module '$1' not found in $(basename "$kdir") (built in, or misspelt?)"
    local deps=${line##* } d
    if [[ $deps != - ]]; then
      for d in ${deps//,/ }; do _visit "$d"; done
    fi
    CLOSURE+=("$n")
  }
  for x in "$@"; do _visit "$x"; done
}

copy_modules() {   # KDIR MODDIR NAME...: decompress the closure of NAMEs into KDIR/modules
  local kdir=$1 moddir=$2; shift 2
  local n path
  closure "$kdir" "$@"
  for n in "${CLOSURE[@]}"; do
    [[ -f $kdir/modules/$n.ko ]] && continue
    path=$(awk -v n="$n" '$1 == n { print $2; exit }' "$kdir/modules.idx")
    decompress_ko "$moddir/$path" "$kdir/modules/$n.ko"
  done
}

ensure_modules() {   # make sure every module of the load list is in the cache (re-extract if not)
  local n missing=0
  closure "$kernel_dir" "${modules[@]}"
  for n in "${CLOSURE[@]}"; do [[ -f $kernel_dir/modules/$n.ko ]] || missing=1; done
  [[ $missing == 0 ]] && return
  local deb key; key=$(basename "$kernel_dir")
  deb=$(ls "$cache/debs/${key}_"*.deb 2>/dev/null | head -n 1) || true
  [[ -n $deb ]] || die "module(s) missing from the cache and $cache/debs/${key}_*.deb is gone; delete $kernel_dir and retry"
  local tmp=$cache/kernel-v1/.tmp.$$
  rm -rf "$tmp"; mkdir -p "$tmp"
  dpkg-deb -x "$deb" "$tmp"
  local moddir; moddir=$(ls -d "$tmp"/lib/modules/*/ "$tmp"/usr/lib/modules/*/ 2>/dev/null | head -n 1) || true
  [[ -n $moddir ]] || die "no lib/modules/<kver>/ in $deb"
  note "extracting module(s) not yet cached from $(basename "$deb")"
  copy_modules "$kernel_dir" "${moddir%/}" "${modules[@]}"
  rm -rf "$tmp"
}

kernel_dir=''
t_prep0=$(date +%s.%N)
{
  flock -w 600 9 || die "timed out waiting for the cache lock $cache/.lock"
  rm -rf "$cache"/kernel-v1/.tmp.*   # left by an interrupted extraction (we hold the lock)
  ensure_kernel
  ensure_modules
} 9>"$cache/.lock"
kver=$(cat "$kernel_dir/kver")
closure "$kernel_dir" "${modules[@]}"
load_order=("${CLOSURE[@]}")

# ------------------------------------------------------------------------------------------------
# Initramfs
# ------------------------------------------------------------------------------------------------
root=$work/root
mkdir -p "$root"/{bin,sbin,usr/bin,usr/sbin,lib64,proc,sys,dev,tmp,run,out,scopekin,etc,root} \
         "$root/lib/modules/$kver"
declare -A libdirs=()

copy_libs() {   # copy the shared libraries and loader of ELF file $1 to the same paths in the guest
  local line lib
  local ldd_out
  ldd_out=$(ldd "$1" 2>/dev/null) || return 0       # static or not ELF: nothing to copy
  while IFS= read -r line; do
    lib=''
    if [[ $line =~ =\>\ (/[^ ]+)\ \( ]]; then lib=${BASH_REMATCH[1]}
    elif [[ $line =~ ^[[:space:]]*(/[^ ]+)\ \( ]]; then lib=${BASH_REMATCH[1]}
    elif [[ $line == *'=> not found'* ]]; then die "ldd $1: $line"
    fi
    [[ -n $lib ]] || continue
    if [[ ! -e $root$lib ]]; then
      mkdir -p "$root$(dirname "$lib")"
      cp -L "$lib" "$root$lib"
    fi
    libdirs[$(dirname "$lib")]=1
  done <<<"$ldd_out"
}

install_file() {   # HOST GUEST
  local src=$1 dst=$2
  [[ $dst == /* ]] || usage_die "guest path '$dst' must be absolute"
  [[ -e $src ]] || usage_die "host file '$src' not found"
  mkdir -p "$root$(dirname "$dst")"
  rm -rf "${root:?}$dst"
  if [[ -d $src ]]; then cp -a "$src" "$root$dst"; else cp -L "$src" "$root$dst"; fi
}

# busybox; /init creates the other applet links with "busybox --install -s", which keeps files
# that already exist (so a --bin named like an applet wins).
cp -L "$busybox" "$root/bin/busybox"
copy_libs "$busybox"
ln -s busybox "$root/bin/sh"

for n in "${load_order[@]}"; do cp "$kernel_dir/modules/$n.ko" "$root/lib/modules/$kver/$n.ko"; done

for b in "${bins[@]}"; do
  src=${b%%:*}
  if [[ $b == *:* ]]; then name=${b#*:}; else name=${src##*/}; fi
  [[ -f $src ]] || usage_die "--bin: '$src' not found"
  [[ $name == /* ]] || name=/bin/$name
  install_file "$src" "$name"
  chmod +x "$root$name"
  copy_libs "$src"
done
for f in "${files[@]}"; do
  [[ $f == *:/* ]] || usage_die "--file needs HOSTPATH:/GUEST/PATH, got '$f'"
  install_file "${f%:/*}" "/${f##*:/}"
done
cp "$script" "$root/scopekin/script.sh"

nonce=$(od -An -N6 -tx1 /dev/urandom | tr -d ' \n')   # markers the guest script cannot fake by accident
send_out=0
[[ -n $out ]] && send_out=1
ld_path=$(printf '%s\n' "${!libdirs[@]}" | sort | paste -sd: -)
args_q=''
for a in "${script_args[@]}"; do args_q+=" $(printf '%q' "$a")"; done

cat > "$root/init" <<EOF
#!/bin/sh
# Generated by vm_run.sh.  PID 1 of the scopekin SocketCAN test VM.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin HOME=/root SCOPEKIN_VM=1
export LD_LIBRARY_PATH='$ld_path'
/bin/busybox --install -s
mount -t devtmpfs devtmpfs /dev 2>/dev/null
exec </dev/console >/dev/console 2>&1
halt_vm() { sync; poweroff -f; reboot -f; echo o > /proc/sysrq-trigger; sleep 5; exit 1; }
setup_failed() { echo "SCOPEKIN_VM_SETUP_FAILED[$nonce]: \$*"; halt_vm; }
mount -t proc proc /proc || setup_failed "mount /proc"
mount -t sysfs sysfs /sys || setup_failed "mount /sys"
mkdir -p /dev/pts /dev/shm
mount -t devpts devpts /dev/pts
mount -t tmpfs tmpfs /dev/shm
mount -t tmpfs tmpfs /tmp
mount -t tmpfs tmpfs /run
for m in ${load_order[*]}; do
  insmod /lib/modules/$kver/\$m.ko || setup_failed "insmod \$m"
done
ip link set up dev lo
i=0
while [ \$i -lt $vcan_count ]; do
  ip link add dev vcan\$i type vcan || setup_failed "ip link add dev vcan\$i type vcan"
  ip link set up dev vcan\$i || setup_failed "ip link set up dev vcan\$i"
  i=\$((i + 1))
done
read up _ < /proc/uptime
echo "SCOPEKIN_VM_READY[$nonce] kernel=$kver uptime=\$up"
cd /tmp
/bin/sh /scopekin/script.sh$args_q
rc=\$?
read up _ < /proc/uptime
if [ "$send_out" = 1 ]; then
  stty -F /dev/ttyS1 raw -echo 2>/dev/null
  { echo "SCOPEKIN_OUT_BEGIN[$nonce]"; tar -c -C /out . | base64; echo "SCOPEKIN_OUT_END[$nonce]"; } > /dev/ttyS1 \\
    || echo "SCOPEKIN_VM_SETUP_FAILED[$nonce]: sending /out on /dev/ttyS1"
fi
echo "SCOPEKIN_VM_EXIT[$nonce]=\$rc uptime=\$up"
halt_vm
EOF
chmod +x "$root/init"

initrd=$work/initrd.cpio
(cd "$root" && find . -print0 | LC_ALL=C sort -z | cpio --null -o -H newc -R 0:0 --quiet) > "$initrd"
t_prep1=$(date +%s.%N)

# ------------------------------------------------------------------------------------------------
# QEMU
# ------------------------------------------------------------------------------------------------
console=$work/console.log
boot_image=$kernel_dir/vmlinuz
if [[ -f $kernel_dir/vmlinux && -z ${SCOPEKIN_VM_BZIMAGE:-} ]]; then boot_image=$kernel_dir/vmlinux; fi
serial2=$work/serial1.txt
: > "$serial2"
qemu=(qemu-system-x86_64 -M pc -m "$memory" -smp 1 -no-user-config -nodefaults -display none
      -no-reboot -pidfile "$qemu_pid_file"
      -kernel "$boot_image" -initrd "$initrd"
      -append "console=ttyS0 quiet panic=-1"
      -serial stdio -serial "file:$serial2")
if [[ $accel == kvm ]]; then qemu+=(-accel kvm -cpu host); else qemu+=(-accel tcg); fi

ready_file=$work/ready_at
t0=$(date +%s.%N)
set +e
{
  timeout --signal=TERM --kill-after=5 "$timeout_s" "${qemu[@]}" </dev/null 2>"$work/qemu.stderr"
  echo $? > "$work/qemu.rc"
} | while IFS= read -r line || [[ -n $line ]]; do
      line=${line%$'\r'}
      printf '%s\n' "$line" >> "$console"
      [[ $quiet == 1 ]] || printf '%s\n' "$line"
      if [[ $line == *"SCOPEKIN_VM_READY[$nonce]"* && ! -e $ready_file ]]; then
        date +%s.%N > "$ready_file"
      fi
    done
set -e
t1=$(date +%s.%N)
qemu_rc=$(cat "$work/qemu.rc" 2>/dev/null || echo 255)

secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }
summary="kernel $kver ($(basename "$kernel_dir"), $(basename "$boot_image")), accel $accel"
summary+=", prepare $(secs "$t_prep0" "$t_prep1") s"
if [[ -e $ready_file ]]; then
  guest_up=$(grep -a -o "SCOPEKIN_VM_READY\[$nonce\].*uptime=[0-9.]*" "$console" | sed 's/.*uptime=//' | head -n 1)
  summary+=", boot to script start $(secs "$t0" "$(cat "$ready_file")") s (guest uptime ${guest_up} s)"
fi
summary+=", QEMU wall time $(secs "$t0" "$t1") s"

fail() {   # message, exit status
  if [[ -n $out ]]; then cp "$console" "$out/console.log"; fi
  if [[ $quiet == 1 ]]; then
    echo "---- last 40 lines of the guest console ----" >&2
    tail -n 40 "$console" >&2 || true
    echo "--------------------------------------------" >&2
  fi
  [[ -s $work/qemu.stderr ]] && { echo "QEMU stderr:" >&2; cat "$work/qemu.stderr" >&2; }
  note "$summary"
  printf '%s: FAILED: %s\n' "$PROG" "$1" >&2
  exit "$2"
}

[[ $qemu_rc == 124 || $qemu_rc == 137 ]] && fail "timeout: the VM did not finish within ${timeout_s} s (QEMU killed)" 124
setup_msg=$(grep -a -o "SCOPEKIN_VM_SETUP_FAILED\[$nonce\].*" "$console" | head -n 1) || true
[[ -z $setup_msg ]] || fail "guest setup failed: ${setup_msg#*]: }" 125
exit_line=$(grep -a -o "SCOPEKIN_VM_EXIT\[$nonce\]=[0-9]*" "$console" | tail -n 1) || true
if [[ -z $exit_line ]]; then
  if [[ -e $ready_file ]]; then
    fail "no exit marker on the console (the guest script killed init or the kernel crashed; QEMU exit $qemu_rc)" 125
  fi
  fail "the VM did not reach the guest script (boot failure; QEMU exit $qemu_rc)" 125
fi
[[ $qemu_rc == 0 ]] || fail "QEMU exited with status $qemu_rc" 125
rc=${exit_line##*=}

if [[ -n $out ]]; then
  tr -d '\r' < "$serial2" > "$work/serial1.unix"
  if ! grep -q -x "SCOPEKIN_OUT_END\[$nonce\]" "$work/serial1.unix"; then
    fail "the guest's /out transfer on the second serial port is incomplete" 125
  fi
  sed -n "/^SCOPEKIN_OUT_BEGIN\[$nonce\]\$/,/^SCOPEKIN_OUT_END\[$nonce\]\$/p" "$work/serial1.unix" \
    | sed '1d;$d' | base64 -d > "$work/out.tar" || fail "cannot decode the guest's /out transfer" 125
  tar -x -C "$out" -f "$work/out.tar" || fail "cannot unpack the guest's /out transfer" 125
  cp "$console" "$out/console.log"
  printf '%s\nexit %s\n' "$summary" "$rc" > "$out/vm_run.log"
fi

note "$summary"
if [[ $rc != 0 ]]; then
  if [[ $quiet == 1 ]]; then
    echo "---- last 40 lines of the guest console ----" >&2
    tail -n 40 "$console" >&2
  fi
  note "guest script exited with status $rc"
fi
exit "$rc"
