#!/usr/bin/env python3
"""Budget measurements of scopekin's firmware kinetics (instructions, RAM, flash, stack, heap
after init): run, check, report.

Subcommands (each is one CTest test of label `budget`, wired in tests/budget/CMakeLists.txt):

  m4-step      runs the Cortex-M4 step runner on QEMU (instructions and stack per step, SysTick
               calibration), checks the bounds, writes the part step_cortex_m4.json
  m4-memory    sizes the minimal Cortex-M4 firmware image (flash, static RAM) with objdump, runs it
               for its stack, adds the worst step/init stack from step_cortex_m4.json, checks that
               no allocator is linked, checks the bounds, writes memory_cortex_m4.json
  callgrind    host: Ir per step of kinetics::step under valgrind --tool=callgrind, writes
               callgrind_host.json (reported, never asserted)
  merge        merges the parts of a build into build/<preset>/budget.json

Every number is a deterministic count (instructions, bytes, calls), never wall-clock time.
Python 3 standard library only.
"""
import argparse
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile

KEYS = (
    "instructions_per_step_max",
    "ram_bytes",
    "flash_bytes",
    "stack_bytes",
    "heap_allocations_after_init",
)

RAM_START, RAM_END = 0x20000000, 0x40000000  # mps2-an386 data memory (mps2_an386.ld)

# Allocator entry points that must not be in a Cortex-M4 image (newlib, libstdc++ Itanium ABI
# names for operator new/delete on a 32-bit target).
HEAP_SYMBOL = re.compile(
    r"^(_?_?(malloc|calloc|realloc|free|memalign|aligned_alloc|posix_memalign|valloc|pvalloc)"
    r"(_r)?|_sbrk(_r)?|_malloc_trim_r|_mallinfo_r|_Znw\w*|_Zna\w*|_Zdl\w*|_Zda\w*)$")


def fail(message):
    print(f"budget.py: {message}", file=sys.stderr)
    return 1


def write_json(path, data):
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n", encoding="utf-8")
    os.replace(tmp, path)
    print(f"budget.py: wrote {path}")


def run_and_echo(command, timeout):
    """Runs command, echoes its output, returns (exit status, output)."""
    print("budget.py: running " + " ".join(str(c) for c in command), flush=True)
    proc = subprocess.run([str(c) for c in command], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout, check=False)
    sys.stdout.write(proc.stdout)
    sys.stdout.flush()
    return proc.returncode, proc.stdout


def discard_stale(path):
    """Removes a part left by an earlier run, so a failed run can never be reported."""
    try:
        pathlib.Path(path).unlink()
    except FileNotFoundError:
        pass


def check_build_type(args):
    if args.require_build_type and args.build_type != args.require_build_type:
        return fail(f"budget numbers are defined for CMAKE_BUILD_TYPE={args.require_build_type} "
                    f"(the preset's flags), this build is '{args.build_type}'")
    return 0


def budget_lines(output):
    """The JSON objects of the program's '@budget {...}' lines."""
    records = []
    for line in output.splitlines():
        if line.startswith("@budget "):
            records.append(json.loads(line[len("@budget "):]))
    return records


# --- m4-step ------------------------------------------------------------------------------------

def cmd_m4_step(args):
    discard_stale(args.json)
    if check_build_type(args):
        return 1
    status, output = run_and_echo([args.emulator, args.elf], args.timeout)
    records = budget_lines(output)
    calibration = next((r["calibration"] for r in records if "calibration" in r), None)
    scenarios = [r["scenario"] for r in records if "scenario" in r]
    if calibration is None or not scenarios:
        return fail("the runner printed no calibration or no scenario results "
                    f"(exit status {status})")

    per_scenario = {}
    worst_instructions = 0
    worst_stack = 0
    for s in scenarios:
        k = s["instructions_per_tick"]
        entry = {
            "steps": s["steps"],
            "instructions_per_step_max": s["ticks_max"] * k,
            "instructions_per_step_mean": round(s["ticks_sum"] * k / s["steps"], 1),
            "instructions_max_at_step": s["ticks_max_at_step"],
            "stack_bytes": s["stack_bytes"],
            "stack_max_at_step": s["stack_max_at_step"],
            "init_instructions": s["init_ticks"] * k,
            "init_stack_bytes": s["init_stack_bytes"],
        }
        per_scenario[s["name"]] = entry
        worst_instructions = max(worst_instructions, entry["instructions_per_step_max"])
        worst_stack = max(worst_stack, entry["stack_bytes"])
        print(f"[ budget ] {s['name']}: {s['steps']} steps, instructions per step max "
              f"{entry['instructions_per_step_max']} (at step {entry['instructions_max_at_step']}),"
              f" mean {entry['instructions_per_step_mean']}; stack of step {entry['stack_bytes']} B;"
              f" init {entry['init_instructions']} instructions, {entry['init_stack_bytes']} B stack")

    resolution = calibration["instructions_per_tick_assumed"]
    part = {
        "instructions_per_step_max": worst_instructions,
        "stack_bytes": worst_stack,
        "scenarios": per_scenario,
        "cortex_m4_step": {
            "instructions_budget": args.budget_instructions,
            "stack_budget_bytes": args.budget_stack,
            "instructions_resolution": resolution,
            "instructions_method": "SysTick on the processor clock (25 MHz) under qemu-system-arm "
                                   "-M mps2-an386 -icount shift=0: 1 instruction = 1 ns, 1 tick = "
                                   "40 ns = 40 instructions; counter restarted per step, wraps "
                                   "counted by the SysTick exception",
            "stack_method": "stack painting: the whole free stack holds a pattern before each "
                            "call, the lowest overwritten word after it gives the depth (the "
                            "runner has 64 KiB of stack)",
            "calibration": calibration,
            "build_type": args.build_type,
            "compile_flags": " ".join(args.flags.split()),
        },
    }
    write_json(args.json, part)

    errors = []
    if status != 0:
        errors.append(f"the runner failed (exit status {status}: failed checks, see above)")
    if (worst_instructions + resolution) > args.budget_instructions:
        errors.append(f"instructions per step {worst_instructions} (+{resolution} resolution) > "
                      f"budget {args.budget_instructions}")
    if worst_stack > args.budget_stack:
        errors.append(f"stack of step {worst_stack} B > budget {args.budget_stack} B")
    for e in errors:
        fail(e)
    if not errors:
        print(f"[ budget ] PASS: instructions_per_step_max {worst_instructions} <= "
              f"{args.budget_instructions}, stack_bytes {worst_stack} <= {args.budget_stack}")
    return 1 if errors else 0


# --- m4-memory ----------------------------------------------------------------------------------

def sections(objdump, elf):
    """[(name, size, vma, lma, flags)] from objdump -h."""
    out = subprocess.run([objdump, "-h", elf], stdout=subprocess.PIPE, text=True,
                         check=True).stdout
    lines = out.splitlines()
    result = []
    for i, line in enumerate(lines):
        m = re.match(r"^\s*\d+\s+(\S+)\s+([0-9a-fA-F]+)\s+([0-9a-fA-F]+)\s+([0-9a-fA-F]+)\s", line)
        if m and i + 1 < len(lines):
            flags = {f.strip() for f in lines[i + 1].split(",")}
            result.append((m.group(1), int(m.group(2), 16), int(m.group(3), 16),
                           int(m.group(4), 16), flags))
    return result


def heap_symbols(nm, elf):
    out = subprocess.run([nm, elf], stdout=subprocess.PIPE, text=True, check=True).stdout
    found = []
    for line in out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and HEAP_SYMBOL.match(parts[-1]):
            found.append(parts[-1])
    return sorted(set(found))


def cmd_m4_memory(args):
    discard_stale(args.json)
    if check_build_type(args):
        return 1
    secs = sections(args.objdump, args.image)
    flash_sections = {n: s for n, s, vma, lma, f in secs if "ALLOC" in f and "LOAD" in f}
    ram_sections = {n: s for n, s, vma, lma, f in secs
                    if "ALLOC" in f and RAM_START <= vma < RAM_END and n != ".stack"}
    reserved_stack = sum(s for n, s, vma, lma, f in secs if n == ".stack")
    flash = sum(flash_sections.values())
    static_ram = sum(ram_sections.values())

    status, output = run_and_echo([args.emulator, args.image], args.timeout)
    image = next((r["image"] for r in budget_lines(output) if "image" in r), None)
    if status != 0 or image is None:
        return fail(f"the firmware image did not run to the end (exit status {status})")

    step_part = json.loads(pathlib.Path(args.step_part).read_text(encoding="utf-8"))
    step_stack = step_part["stack_bytes"]
    init_stack = max(s["init_stack_bytes"] for s in step_part["scenarios"].values())
    stack = max(image["stack_high_water_bytes"],
                image["stack_depth_at_call_bytes"] + max(step_stack, init_stack))
    ram = static_ram + stack

    heap = {str(elf): heap_symbols(args.nm, elf) for elf in [args.image] + args.no_heap}

    part = {
        "ram_bytes": ram,
        "flash_bytes": flash,
        "cortex_m4_memory": {
            "image": os.path.basename(args.image),
            "ram_budget_bytes": args.budget_ram,
            "flash_budget_bytes": args.budget_flash,
            "flash_sections": flash_sections,
            "static_ram_sections": ram_sections,
            "static_ram_bytes": static_ram,
            "stack_bytes_in_ram": stack,
            "stack_reserved_by_linker_script_bytes": reserved_stack,
            "image_stack_high_water_bytes": image["stack_high_water_bytes"],
            "image_stack_depth_at_step_call_bytes": image["stack_depth_at_call_bytes"],
            "worst_step_stack_bytes": step_stack,
            "worst_init_stack_bytes": init_stack,
            "ram_method": "static RAM (.data + .bss of the image, objdump -h) + stack, where stack "
                          "= max(image's painted high-water mark, image's depth at the call of "
                          "step + worst of step/init stack over all scenarios)",
            "flash_method": "every ALLOC+LOAD section of the image (vectors, text, rodata, exidx, "
                            "init arrays, .data image), objdump -h",
            "allocator_symbols": {os.path.basename(k): v for k, v in heap.items()},
            "heap": "no allocator is linked: the images contain none of malloc/free/_sbrk/"
                    "operator new/delete (nm); _sbrk in startup.c would fail anyway",
            "build_type": args.build_type,
            "compile_flags": " ".join(args.flags.split()),
        },
    }
    write_json(args.json, part)
    print(f"[ budget ] flash {flash} B ({', '.join(f'{n} {s}' for n, s in flash_sections.items())})")
    print(f"[ budget ] RAM {ram} B = static {static_ram} B "
          f"({', '.join(f'{n} {s}' for n, s in ram_sections.items())}) + stack {stack} B")

    errors = []
    if ram > args.budget_ram:
        errors.append(f"RAM {ram} B > budget {args.budget_ram} B")
    if flash > args.budget_flash:
        errors.append(f"flash {flash} B > budget {args.budget_flash} B")
    for elf, symbols in heap.items():
        if symbols:
            errors.append(f"{elf} links allocator symbols: {', '.join(symbols)}")
    for e in errors:
        fail(e)
    if not errors:
        print(f"[ budget ] PASS: ram_bytes {ram} <= {args.budget_ram}, flash_bytes {flash} <= "
              f"{args.budget_flash}, no allocator linked")
    return 1 if errors else 0


# --- callgrind ----------------------------------------------------------------------------------

def cmd_callgrind(args):
    discard_stale(args.json)
    with tempfile.TemporaryDirectory() as tmp:
        out_file = pathlib.Path(tmp) / "callgrind.out"
        command = [args.valgrind, "--tool=callgrind", f"--callgrind-out-file={out_file}",
                   "--collect-atstart=no", f"--toggle-collect={args.toggle}", args.program]
        if args.scenario:
            command += ["--scenario", args.scenario]
        if args.max_steps:
            command += ["--max-steps", str(args.max_steps)]
        status, output = run_and_echo(command, args.timeout)
        if status != 0:
            return fail(f"valgrind/program failed (exit status {status})")
        m = re.search(r"scenario=(\S+) steps=(\d+)", output)
        if not m:
            return fail("the program did not report its steps")
        scenario, steps = m.group(1), int(m.group(2))
        text = out_file.read_text(encoding="utf-8", errors="replace")
    events = re.search(r"^events:\s*(.+)$", text, re.M)
    totals = re.search(r"^(?:summary|totals):\s*(.+)$", text, re.M)
    if not events or not totals:
        return fail("no events/summary line in the callgrind output")
    values = dict(zip(events.group(1).split(), (int(v) for v in totals.group(1).split())))
    ir = values.get("Ir", 0)
    if ir == 0 or steps == 0:
        return fail(f"callgrind collected no instructions inside '{args.toggle}' "
                    "(was step inlined or renamed?)")
    per_step = ir / steps
    print(f"[ budget ] host callgrind: {scenario}, {steps} steps, {ir} Ir inside step, "
          f"{per_step:.1f} Ir per step")
    write_json(args.json, {
        "host_callgrind": {
            "scenario": scenario,
            "steps": steps,
            "ir_total": ir,
            "ir_per_step_mean": round(per_step, 1),
            "toggle_collect": args.toggle,
            "build_type": args.build_type,
            "compile_flags": " ".join(args.flags.split()),
            "note": "x86-64 instructions (Ir) executed inside kinetics::step and its callees; "
                    "reported, not asserted",
        },
        "scenarios": {scenario: {"host_ir_per_step_mean": round(per_step, 1)}},
    })
    return 0


# --- merge --------------------------------------------------------------------------------------

def load_parts(directory):
    parts = {}
    d = pathlib.Path(directory)
    if d.is_dir():
        for p in sorted(d.glob("*.json")):
            parts[p.stem] = json.loads(p.read_text(encoding="utf-8"))
    return parts


def cmd_merge(args):
    own = load_parts(args.parts)
    missing = [r for r in args.require if r not in own]
    if missing:
        return fail(f"missing parts in {args.parts}: {', '.join(missing)} "
                    "(run the whole 'budget' label: ctest -L budget)")
    budgets = {
        "instructions_per_step_max": args.budget_instructions,
        "ram_bytes": args.budget_ram,
        "flash_bytes": args.budget_flash,
        "stack_bytes": args.budget_stack,
        "heap_allocations_after_init": args.budget_heap,
    }
    report = {k: None for k in KEYS}
    sources = {}
    scenarios = {}
    details = {}

    def absorb(parts, origin, fill_only):
        for name, part in parts.items():
            for key in KEYS:
                if key in part and (not fill_only or report[key] is None):
                    if report[key] is not None and sources.get(key, "").split(":")[0] == origin:
                        return fail(f"two parts of {origin} report {key}")
                    report[key] = part[key]
                    sources[key] = f"{origin}:{name}.json"
            for scenario, values in part.get("scenarios", {}).items():
                merged = scenarios.setdefault(scenario, {})
                for k, v in values.items():
                    if k not in merged:
                        merged[k] = v
            for k, v in part.items():
                if k not in KEYS and k != "scenarios" and k not in details:
                    details[k] = v
        return 0

    if absorb(own, args.preset, False):
        return 1
    for extra in args.fallback_parts:
        origin = pathlib.Path(extra).resolve().parent.name
        if absorb(load_parts(extra), origin, True):
            return 1

    within = {k: (None if report[k] is None else report[k] <= budgets[k]) for k in KEYS}
    out = dict(report)
    out.update({
        "preset": args.preset,
        "budgets": budgets,
        "within_budget": within,
        "sources": sources,
        "scenarios": scenarios,
        "details": details,
    })
    write_json(args.out, out)
    for k in KEYS:
        v = "not measured on this preset" if report[k] is None else report[k]
        print(f"[ budget ] {k}: {v} (budget {budgets[k]}"
              f"{', from ' + sources[k] if k in sources else ''})")
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    def common(p):
        p.add_argument("--json", required=True, help="part file to write")
        p.add_argument("--timeout", type=float, default=110.0)
        p.add_argument("--build-type", default="")
        p.add_argument("--flags", default="")
        p.add_argument("--require-build-type", default="",
                       help="fail unless --build-type is this (the numbers hold for fixed flags)")

    p = sub.add_parser("m4-step")
    common(p)
    p.add_argument("--emulator", required=True)
    p.add_argument("--elf", required=True)
    p.add_argument("--budget-instructions", type=int, required=True)
    p.add_argument("--budget-stack", type=int, required=True)
    p.set_defaults(run=cmd_m4_step)

    p = sub.add_parser("m4-memory")
    common(p)
    p.add_argument("--objdump", required=True)
    p.add_argument("--nm", required=True)
    p.add_argument("--emulator", required=True)
    p.add_argument("--image", required=True)
    p.add_argument("--no-heap", nargs="*", default=[], help="more ELFs that must link no allocator")
    p.add_argument("--step-part", required=True)
    p.add_argument("--budget-ram", type=int, required=True)
    p.add_argument("--budget-flash", type=int, required=True)
    p.set_defaults(run=cmd_m4_memory)

    p = sub.add_parser("callgrind")
    common(p)
    p.add_argument("--valgrind", required=True)
    p.add_argument("--program", required=True)
    p.add_argument("--toggle", default="scopekin::kinetics::step(*")
    p.add_argument("--scenario", default="")
    p.add_argument("--max-steps", type=int, default=0)
    p.set_defaults(run=cmd_callgrind)

    p = sub.add_parser("merge")
    p.add_argument("--parts", required=True)
    p.add_argument("--fallback-parts", nargs="*", default=[])
    p.add_argument("--out", required=True)
    p.add_argument("--preset", required=True)
    p.add_argument("--require", nargs="*", default=[])
    p.add_argument("--budget-instructions", type=int, required=True)
    p.add_argument("--budget-ram", type=int, required=True)
    p.add_argument("--budget-flash", type=int, required=True)
    p.add_argument("--budget-stack", type=int, required=True)
    p.add_argument("--budget-heap", type=int, required=True)
    p.set_defaults(run=cmd_merge)

    args = parser.parse_args()
    try:
        return args.run(args)
    except subprocess.TimeoutExpired as e:
        return fail(f"timed out: {e}")


if __name__ == "__main__":
    sys.exit(main())
