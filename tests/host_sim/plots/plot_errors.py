#!/usr/bin/python3
"""Error-path tests of host_sim/plots/plot_run.py (run by CTest, see CMakeLists.txt).

Usage: plot_errors.py CASE WORK_DIR
CASE: malformed_firmware  a non-numeric cell in firmware.csv -> exit 2, message names file, line, column
      missing_file        world.csv absent                   -> exit 2, message names world.csv
      unwritable_output   forces.png is a directory          -> exit 3, message names forces.png
      help                --help                             -> exit 0, usage on stdout
Each case makes its own small sample run (make_sample_run.py, 2 s) in WORK_DIR/CASE.
"""
import csv
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
PLOT = os.path.join(ROOT, "host_sim", "plots", "plot_run.py")
GENERATOR = os.path.join(HERE, "make_sample_run.py")


def run(args):
    r = subprocess.run([sys.executable] + args, capture_output=True, text=True, timeout=120)
    sys.stdout.write(f"$ {' '.join(args)}\n-> exit {r.returncode}\n{r.stdout}{r.stderr}")
    return r


def expect(cond, what):
    if not cond:
        print(f"FAIL: {what}")
        sys.exit(1)
    print(f"ok: {what}")


def sample(run_dir):
    r = run([GENERATOR, run_dir, "--duration-s", "2"])
    expect(r.returncode == 0, "make_sample_run.py succeeds")


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    case, work = argv[1], argv[2]
    run_dir = os.path.join(work, case)
    if case == "help":
        r = run([PLOT, "--help"])
        expect(r.returncode == 0, "--help exits 0")
        expect("RUN_DIR" in r.stdout and "--quiet" in r.stdout, "--help prints the usage")
        return 0
    if os.path.isdir(os.path.join(run_dir, "forces.png")):  # left by an earlier unwritable_output run
        os.rmdir(os.path.join(run_dir, "forces.png"))
    sample(run_dir)
    if case == "malformed_firmware":
        path = os.path.join(run_dir, "firmware.csv")
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        col = rows[0].index("tip_path_mm")
        line = 7  # the header is line 1
        rows[line - 1][col] = "12.5mm"
        with open(path, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
        r = run([PLOT, run_dir, "--quiet"])
        expect(r.returncode == 2, "a non-numeric cell in firmware.csv exits 2")
        want = f"firmware.csv: line {line}, column {col + 1} (tip_path_mm): '12.5mm' is not a finite number"
        expect(want in r.stderr, f"the message names the file, line and column: {want!r}")
        expect(not os.path.exists(os.path.join(run_dir, "forces.png")), "nothing is written")
    elif case == "missing_file":
        os.remove(os.path.join(run_dir, "world.csv"))
        r = run([PLOT, run_dir])
        expect(r.returncode == 2, "a missing world.csv exits 2")
        expect(os.path.join(run_dir, "world.csv") + ": missing" in r.stderr, "the message names world.csv")
        expect(r.stdout == "", "nothing is reported written")
    elif case == "unwritable_output":
        os.mkdir(os.path.join(run_dir, "forces.png"))
        r = run([PLOT, run_dir])
        expect(r.returncode == 3, "an output that cannot be written exits 3")
        expect("forces.png: cannot write" in r.stderr, "the message names forces.png")
    else:
        sys.stderr.write(f"plot_errors.py: unknown case {case!r}\n{__doc__}")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
