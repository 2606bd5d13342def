"""What the checks of host_sim/evaluate's scripts share: a fresh work folder, and `expect`, which
prints each check and keeps the failed ones in `failures` (the script exits non-zero if any)."""
import os
import shutil

failures = []


def fresh_folder(path):
    """An empty folder at path (what a previous run left there removed)."""
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)


def expect(ok, what):
    print(("ok: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)
