"""What the studies of host_sim/evaluate share: an evaluation's case folders, a complete case's
summary, its CSVs read as named columns, a table written as CSV, and the bad input they refuse
(exit status 2)."""
import csv
import json
import os

import numpy as np


class BadInput(Exception):
    """Input a study refuses: its message names the file and what is wrong."""


def case_folders(eval_dir):
    """(name, folder) of each case of an evaluation (EVAL_DIR/cases/NAME), sorted by name."""
    cases_dir = os.path.join(eval_dir, "cases")
    if not os.path.isdir(cases_dir):
        raise BadInput(f"{eval_dir}: no cases/ folder (an evaluation's output?)")
    return [(name, os.path.join(cases_dir, name)) for name in sorted(os.listdir(cases_dir))]


def columns(path, names):
    """The named columns of a CSV as float arrays (empty cells: NaN; no rows: empty arrays)."""
    if not os.path.isfile(path):
        raise BadInput(f"{path}: missing")
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise BadInput(f"{path}: empty")
        missing = [n for n in names if n not in header]
        if missing:
            raise BadInput(f"{path}: no column {', '.join(missing)}")
        index = [header.index(n) for n in names]
        rows = [[float(r[i]) if i < len(r) and r[i] != "" else np.nan for i in index] for r in reader]
    return {n: np.array([r[k] for r in rows]) for k, n in enumerate(names)}


def complete_summary(folder):
    """The case's summary.json if the case ran to completion, else None (no summary, failed)."""
    path = os.path.join(folder, "summary.json")
    if not os.path.isfile(path):
        return None
    try:
        summary = json.load(open(path))
    except ValueError as e:
        raise BadInput(f"{path}: not JSON ({e})")
    return summary if summary.get("status") == "complete" else None


def write_rows(path, fieldnames, rows):
    """rows (dicts) as a CSV with the named columns, in that order (other keys left out)."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fieldnames, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
