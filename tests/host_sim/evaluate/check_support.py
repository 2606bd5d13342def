"""What the checks of host_sim/evaluate's scripts share: a fresh work folder, `expect`, which
prints each check and keeps the failed ones in `failures` (the script exits non-zero if any), and
`run_script`, which runs the script under check."""
import os
import shutil
import subprocess
import sys

failures = []


def fresh_folder(path):
    """An empty folder at path (what a previous run left there removed)."""
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)


def expect(ok, what):
    print(("ok: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def run_script(script, *args):
    """Runs a Python script with this interpreter; its CompletedProcess (text output captured)."""
    return subprocess.run([sys.executable, script, *args], capture_output=True, text=True)
