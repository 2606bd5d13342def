#!/usr/bin/python3
"""Draw the gallery of virtual patients written by `scopekin patients`: DIR/gallery.png.

Usage: plot_patients.py DIR [--quiet]

Reads DIR/patients.csv (one row per patient: seed, sigmoid_shape, total_length_mm, ...) and
DIR/centerlines.csv (seed, point, region, x_mm, y_mm, z_mm, inner_radius_mm) and draws one small
panel per patient (at most the first 100): the centerline in the frontal view (x: the patient's
left, to the right as on a radiograph; y: cranial), each region in its colour (the regions'
palette of plot_run.py), the seed as the panel's title. Written as gallery.png.part, then
renamed. Exit status: 0 ok, 2 bad usage or a missing/malformed input (the message names the file,
line and column), 3 an output that cannot be written.
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_run import DPI, REGION_BASE, REGIONS, InputError, OutputError, plt, save  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

MAX_PANELS = 100


def read_csv(path, columns):
    """Rows of PATH as dicts; every column in COLUMNS present, numbers parsed where asked."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (no such file)")
    rows = []
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header is None:
            raise InputError(f"{path}: empty (no header)")
        for name in columns:
            if name not in header:
                raise InputError(f"{path}: line 1: no column '{name}'")
        for line, cells in enumerate(reader, start=2):
            if len(cells) != len(header):
                raise InputError(f"{path}: line {line}: {len(cells)} cells, the header has {len(header)}")
            row = dict(zip(header, cells))
            for name, kind in columns.items():
                if kind is float:
                    try:
                        value = float(row[name])
                    except ValueError:
                        value = math.nan
                    if not math.isfinite(value):
                        raise InputError(f"{path}: line {line}, column {header.index(name) + 1} ({name}): "
                                         f"'{row[name][:80]}' is not a finite number")
                    row[name] = value
                elif kind == "region" and row[name] not in REGION_BASE:
                    raise InputError(f"{path}: line {line}, column {header.index(name) + 1} ({name}): "
                                     f"unknown region '{row[name][:80]}'")
            rows.append(row)
    return rows


def draw(directory, quiet):
    patients = read_csv(os.path.join(directory, "patients.csv"),
                        {"seed": str, "sigmoid_shape": str, "total_length_mm": float})
    points = read_csv(os.path.join(directory, "centerlines.csv"),
                      {"seed": str, "region": "region", "x_mm": float, "y_mm": float})
    if not patients:
        raise InputError(f"{os.path.join(directory, 'patients.csv')}: no patients")
    shown = patients[:MAX_PANELS]
    by_seed = {}
    for p in points:
        by_seed.setdefault(p["seed"], []).append(p)
    columns = math.ceil(math.sqrt(len(shown)))
    rows = math.ceil(len(shown) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(1.9 * columns + 0.4, 2.2 * rows + 0.9), squeeze=False)
    for k, ax in enumerate(axes.flat):
        ax.set_xticks([])
        ax.set_yticks([])
        if k >= len(shown):
            ax.axis("off")
            continue
        patient = shown[k]
        line = by_seed.get(patient["seed"], [])
        if len(line) < 2:
            raise InputError(f"{os.path.join(directory, 'centerlines.csv')}: no centerline for seed {patient['seed']}")
        for a, b in zip(line, line[1:]):
            ax.plot([a["x_mm"], b["x_mm"]], [a["y_mm"], b["y_mm"]], color=REGION_BASE[a["region"]],
                    linewidth=2.2, solid_capstyle="round")
        ax.plot([0], [0], marker="v", color="black", markersize=3)  # the anus
        ax.set_aspect("equal", adjustable="datalim")
        shape = "α" if patient["sigmoid_shape"] == "alpha_prone" else "N"
        ax.set_title(f"seed {patient['seed']}\n{patient['total_length_mm'] / 1000:.2f} m, {shape}", fontsize=7)
    more = f" (the first {len(shown)} of {len(patients)})" if len(patients) > len(shown) else ""
    fig.suptitle(f"{len(patients)} virtual patients{more}: frontal view, patient's left to the right, "
                 "cranial up; N / α: N- or alpha-prone sigmoid", fontsize=9)
    handles = [Line2D([0], [0], color=REGION_BASE[r], linewidth=3, label=r.replace("_", " ")) for r in REGIONS]
    fig.legend(handles=handles, loc="lower center", ncol=len(REGIONS), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.04, 1, 0.95))
    path = os.path.join(directory, "gallery.png")
    save(fig, path)
    if not quiet:
        print(f"plot_patients: wrote {path} ({os.path.getsize(path)} bytes)")


def main(argv=None):
    parser = argparse.ArgumentParser(description="Gallery of virtual patients (scopekin patients).")
    parser.add_argument("directory", help="folder with patients.csv and centerlines.csv")
    parser.add_argument("--quiet", action="store_true", help="print nothing on success")
    args = parser.parse_args(argv)
    try:
        draw(args.directory, args.quiet)
    except InputError as e:
        sys.stderr.write(f"plot_patients: {e}\n")
        return 2
    except OutputError as e:
        sys.stderr.write(f"plot_patients: {e}\n")
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
