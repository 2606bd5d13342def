#!/usr/bin/python3
"""Plot a simulated run: forces.png, advance.png and snapshots.png into RUN_DIR.

Usage: plot_run.py RUN_DIR [--quiet]

Reads RUN_DIR/recording.csv, world.csv, firmware.csv, snapshots.json and summary.json (schema:
host_sim/plots/README.md) and writes three PNGs (150 dpi) into RUN_DIR, printing one line per file
written (unless --quiet). Exit status: 0 ok, 2 bad usage or a missing/malformed input (the message
names the file, line and column), 3 an output that cannot be written.
"""
import argparse
import csv
import json
import math
import os
import re
import sys
import time

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import EllipseCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    import numpy as np
except ImportError as e:  # pragma: no cover - depends on the host
    sys.stderr.write(f"plot_run: {e}: install python3-matplotlib "
                     "(apt-get install -y --no-install-recommends python3-matplotlib)\n")
    sys.exit(2)

DPI = 150
# Okabe & Ito (2008) colour-blind-safe palette
OI = {"black": "#000000", "orange": "#E69F00", "sky": "#56B4E9", "green": "#009E73", "yellow": "#F0E442",
      "blue": "#0072B2", "vermillion": "#D55E00", "purple": "#CC79A7", "grey": "#999999"}
REGIONS = ["rectum", "sigmoid", "descending", "splenic_flexure", "transverse", "hepatic_flexure",
           "ascending", "cecum"]
# neighbouring regions get clearly different hues (the similar pairs are far apart in the body)
REGION_BASE = {"rectum": OI["orange"], "sigmoid": OI["sky"], "descending": OI["green"],
               "splenic_flexure": OI["yellow"], "transverse": OI["purple"], "hepatic_flexure": OI["blue"],
               "ascending": OI["vermillion"], "cecum": OI["grey"]}
ALARM_STYLE = {  # kind -> (label, colour, fill alpha, hatch, marker); self-lock is hatched so that
    # it stays readable where it overlaps the (nested) contact-force warning/critical fills
    "self_lock": ("self-lock", OI["blue"], 0.07, "///", "o"),
    "contact_force_warning": ("contact force warning", OI["yellow"], 0.40, None, "s"),
    "contact_force_critical": ("contact force critical", OI["vermillion"], 0.22, None, "D"),
}
FORCE_CMAP = "viridis"
MAX_SNAPSHOT_PANELS = 6
DRAW_BUCKETS = 2500  # min/max buckets per drawn series (peaks are always kept)


class InputError(Exception):
    """A missing or malformed input (exit 2)."""


# ---------------------------------------------------------------------------------------------
# reading
def _lighten(hex_colour, amount):
    c = np.array(matplotlib.colors.to_rgb(hex_colour))
    return tuple(c + (1.0 - c) * amount)


def read_csv(path, numeric):
    """Read the named columns of a CSV file with a header row (other columns are only counted).

    Every row must have as many cells as the header; in the named columns an empty cell is NaN and
    anything else must be a finite number. Returns (dict name -> numpy array, number of rows).
    Messages give the file's line (the header is line 1) and the column (from 1)."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (no such file)")
    try:
        f = open(path, newline="", encoding="utf-8")
    except OSError as e:
        raise InputError(f"{path}: cannot read: {e.strerror}")
    with f:
        reader = csv.reader(f)
        try:
            header = next(reader)
        except StopIteration:
            raise InputError(f"{path}: line 1: empty file (expected a header row)")
        except csv.Error as e:
            raise InputError(f"{path}: line 1: {e}")
        except UnicodeDecodeError as e:
            raise InputError(f"{path}: not UTF-8 text: {e.reason}")
        header = [h.strip() for h in header]
        seen = {}
        for i, h in enumerate(header):
            if h in seen:
                raise InputError(f"{path}: line 1, column {i + 1}: column '{h}' repeats column {seen[h] + 1}")
            seen[h] = i
        missing = [c for c in numeric if c not in seen]
        if missing:
            raise InputError(f"{path}: line 1: missing column(s): {', '.join(missing)}")
        idx = [seen[c] for c in numeric]
        width = len(header)
        raw, lines = [], []
        try:
            for row in reader:
                if len(row) != width:
                    if not row:
                        raise InputError(f"{path}: line {reader.line_num}: empty line")
                    raise InputError(f"{path}: line {reader.line_num}: {len(row)} cells, the header has {width}")
                raw.append(tuple(row[i] for i in idx))
                lines.append(reader.line_num)
        except csv.Error as e:
            raise InputError(f"{path}: line {reader.line_num}: {e}")
        except UnicodeDecodeError as e:  # decoded in blocks: the line is only a lower bound
            raise InputError(f"{path}: not UTF-8 text after line {reader.line_num}: {e.reason}")
    if not raw:
        raise InputError(f"{path}: line 2: no data rows")
    cols = list(zip(*raw))
    out = {}
    nan = math.nan
    for j, c in enumerate(numeric):
        cells = cols[j]
        try:
            arr = np.array([float(s) if s else nan for s in cells], dtype=float)
            ok = bool(np.all(np.isfinite(arr) | np.array([not s for s in cells])))
        except ValueError:
            ok = False
        if not ok:
            for r, s in enumerate(cells):  # the first bad cell, for the message
                if not s:
                    continue
                try:
                    v = float(s)
                except ValueError:
                    v = None
                if v is None or not math.isfinite(v):
                    raise InputError(f"{path}: line {lines[r]}, column {idx[j] + 1} ({c}): "
                                     f"'{s}' is not a finite number")
        out[c] = arr
    n = len(raw)
    # time must be present and non-decreasing
    if "time_s" in out:
        t = out["time_s"]
        bad = np.nonzero(np.isnan(t))[0]
        if len(bad):
            raise InputError(f"{path}: line {lines[bad[0]]}, column {seen['time_s'] + 1} (time_s): empty")
        back = np.nonzero(np.diff(t) < 0)[0]
        if len(back):
            r = back[0] + 1
            raise InputError(f"{path}: line {lines[r]}, column {seen['time_s'] + 1} (time_s): "
                             f"{t[r]:g} s is before the {t[r - 1]:g} s of line {lines[r - 1]} (time goes backwards)")
    out["_columns"] = {c: seen[c] + 1 for c in numeric}
    out["_lines"] = lines
    return out, n


def check_values(path, data, column, allowed):
    """Each non-empty cell of `column` must be one of `allowed`."""
    v = data[column]
    ok = np.isnan(v) | np.isin(v, list(allowed))
    bad = np.nonzero(~ok)[0]
    if len(bad):
        r = bad[0]
        raise InputError(f"{path}: line {data['_lines'][r]}, column {data['_columns'][column]} ({column}): "
                         f"{v[r]:g} is not one of {', '.join(str(a) for a in sorted(allowed))}")


def read_json(path):
    if not os.path.isfile(path):
        raise InputError(f"{path}: missing (no such file)")

    def bad_constant(s):
        raise ValueError(f"{s} is not a finite number")

    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{path}: cannot read: {e}")
    try:
        return json.loads(text, parse_constant=bad_constant)
    except json.JSONDecodeError as e:
        raise InputError(f"{path}: line {e.lineno}, column {e.colno}: {e.msg}")
    except ValueError as e:  # NaN / Infinity: find where (JSON has no such numbers)
        m = re.search(r'(?<![\w"])(-?Infinity|NaN)(?![\w"])', text)
        if m:
            line = text.count("\n", 0, m.start()) + 1
            col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
            raise InputError(f"{path}: line {line}, column {col}: {e}")
        raise InputError(f"{path}: {e}")


def _num(path, where, v, allow_null=False):
    if v is None and allow_null:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{path}: {where}: expected a finite number, got {json.dumps(v)[:40]}")
    return float(v)


def _points(path, where, v, allow_empty=True):
    if not isinstance(v, list) or (not v and not allow_empty):
        raise InputError(f"{path}: {where}: expected a list of [x, y, z] points")
    out = np.empty((len(v), 3))
    for i, p in enumerate(v):
        if not isinstance(p, list) or len(p) != 3:
            raise InputError(f"{path}: {where}[{i}]: expected [x, y, z]")
        for k in range(3):
            out[i, k] = _num(path, f"{where}[{i}][{k}]", p[k])
    return out


def _vec3(path, where, v):
    if not isinstance(v, list) or len(v) != 3:
        raise InputError(f"{path}: {where}: expected [x, y, z]")
    return np.array([_num(path, f"{where}[{k}]", v[k]) for k in range(3)])


def _obj(path, where, v):
    if not isinstance(v, dict):
        raise InputError(f"{path}: {where}: expected an object")
    return v


def _key(path, where, obj, key):
    if key not in obj:
        raise InputError(f"{path}: {where}: missing key '{key}'")
    return obj[key]


def read_summary(path):
    doc = _obj(path, "top level", read_json(path))
    alarms = _key(path, "top level", doc, "alarms")
    if not isinstance(alarms, list):
        raise InputError(f"{path}: alarms: expected a list")
    out = []
    for i, a in enumerate(alarms):
        w = f"alarms[{i}]"
        _obj(path, w, a)
        kind = _key(path, w, a, "kind")
        if not isinstance(kind, str) or not kind:
            raise InputError(f"{path}: {w}.kind: expected a string")
        raised = _num(path, w + ".raised_s", _key(path, w, a, "raised_s"))
        cleared = _num(path, w + ".cleared_s", a.get("cleared_s"), allow_null=True)
        if cleared is not None and cleared < raised:
            raise InputError(f"{path}: {w}.cleared_s: {cleared:g} s is before raised_s {raised:g} s")
        out.append({"kind": kind, "raised_s": raised, "cleared_s": cleared})
    return out


def read_snapshots(path):
    doc = _obj(path, "top level", read_json(path))
    colon = _obj(path, "colon", _key(path, "top level", doc, "colon"))
    cl = _points(path, "colon.centerline_mm", _key(path, "colon", colon, "centerline_mm"), allow_empty=False)
    if len(cl) < 2:
        raise InputError(f"{path}: colon.centerline_mm: needs at least 2 points")
    radius = _key(path, "colon", colon, "inner_radius_mm")
    if not isinstance(radius, list) or len(radius) != len(cl):
        raise InputError(f"{path}: colon.inner_radius_mm: expected {len(cl)} numbers (one per centerline point)")
    radius = np.array([_num(path, f"colon.inner_radius_mm[{i}]", r) for i, r in enumerate(radius)])
    if np.any(radius <= 0):
        raise InputError(f"{path}: colon.inner_radius_mm[{int(np.argmax(radius <= 0))}]: must be > 0")
    region = _key(path, "colon", colon, "region")
    if not isinstance(region, list) or len(region) != len(cl) or not all(isinstance(r, str) for r in region):
        raise InputError(f"{path}: colon.region: expected {len(cl)} strings (one per centerline point)")
    snaps_in = _key(path, "top level", doc, "snapshots")
    if not isinstance(snaps_in, list):
        raise InputError(f"{path}: snapshots: expected a list")
    snaps = []
    for i, s in enumerate(snaps_in):
        w = f"snapshots[{i}]"
        _obj(path, w, s)
        label = _key(path, w, s, "label")
        if not isinstance(label, str):
            raise InputError(f"{path}: {w}.label: expected a string")
        snap = {"time_s": _num(path, w + ".time_s", _key(path, w, s, "time_s")), "label": label,
                "scope_mm": _points(path, w + ".scope_mm", _key(path, w, s, "scope_mm")),
                "colon_mm": _points(path, w + ".colon_mm", _key(path, w, s, "colon_mm"))}
        if len(snap["colon_mm"]) != len(cl):
            raise InputError(f"{path}: {w}.colon_mm: {len(snap['colon_mm'])} points, "
                             f"colon.centerline_mm has {len(cl)}")
        contacts = _key(path, w, s, "contacts")
        if not isinstance(contacts, list):
            raise InputError(f"{path}: {w}.contacts: expected a list")
        pos, fvec, fn = [], [], []
        for j, c in enumerate(contacts):
            wc = f"{w}.contacts[{j}]"
            _obj(path, wc, c)
            pos.append(_vec3(path, wc + ".position_mm", _key(path, wc, c, "position_mm")))
            fvec.append(_vec3(path, wc + ".force_N", _key(path, wc, c, "force_N")))
            fn.append(_num(path, wc + ".normal_force_N", _key(path, wc, c, "normal_force_N")))
        snap["contact_pos"] = np.array(pos).reshape(-1, 3)
        snap["contact_force"] = np.array(fvec).reshape(-1, 3)
        snap["contact_normal"] = np.array(fn)
        est = _key(path, w, s, "estimated")
        if not isinstance(est, list):
            raise InputError(f"{path}: {w}.estimated: expected a list")
        ep, en, et = [], [], []
        for j, e in enumerate(est):
            we = f"{w}.estimated[{j}]"
            _obj(path, we, e)
            ep.append(_num(path, we + ".path_mm", _key(path, we, e, "path_mm")))
            en.append(_num(path, we + ".normal_N", _key(path, we, e, "normal_N")))
            et.append(_num(path, we + ".tangential_N", _key(path, we, e, "tangential_N")))
        snap["est_path"] = np.array(ep)
        snap["est_force"] = np.hypot(np.array(en), np.array(et))
        snaps.append(snap)
    return {"centerline": cl, "radius": radius, "region": region}, snaps


RECORDING_NUMERIC = ["time_s", "handle_force_N", "handle_torque_Nmm", "insertion_mm",
                     "tip_force_x_N", "tip_force_y_N", "tip_force_z_N"]
WORLD_NUMERIC = ["time_s", "handle_force_N", "handle_torque_Nmm", "insertion_depth_mm", "tip_path_mm",
                 "tip_contact_force_N"]
FIRMWARE_NUMERIC = ["time_s", "tip_path_mm", "advance_efficiency", "self_lock_alarm", "contact_force_level",
                    "station_0_normal_N", "station_0_tangential_N"]


def read_run(run_dir, summary=None):
    if not os.path.isdir(run_dir):
        raise InputError(f"{run_dir}: not a directory")
    p = lambda n: summary if n == "summary.json" and summary else os.path.join(run_dir, n)  # noqa: E731
    # check all files exist first: one message naming every missing one
    names = ["recording.csv", "world.csv", "firmware.csv", "snapshots.json", "summary.json"]
    missing = [n for n in names if not os.path.isfile(p(n))]
    if missing:
        raise InputError("; ".join(f"{p(n)}: missing (no such file)" for n in missing))
    rec, _ = read_csv(p("recording.csv"), RECORDING_NUMERIC)
    world, _ = read_csv(p("world.csv"), WORLD_NUMERIC)
    fw, _ = read_csv(p("firmware.csv"), FIRMWARE_NUMERIC)
    check_values(p("firmware.csv"), fw, "self_lock_alarm", {0, 1})
    check_values(p("firmware.csv"), fw, "contact_force_level", {0, 1, 2})
    colon, snaps = read_snapshots(p("snapshots.json"))
    alarms = read_summary(p("summary.json"))
    return {"recording": rec, "world": world, "firmware": fw, "colon": colon, "snapshots": snaps, "alarms": alarms}


# ---------------------------------------------------------------------------------------------
# drawing helpers
def decimate(t, y, buckets=DRAW_BUCKETS, gap_factor=20.0):
    """Drop empty cells, break the line at gaps (> gap_factor x the median spacing) with NaN, and
    reduce long series to the min and max of each of `buckets` equal-count buckets, so every peak
    and trough survives."""
    ok = ~np.isnan(y)
    t, y = t[ok], y[ok]
    if len(t) < 2:
        return t, y
    dt = np.diff(t)
    pos = dt[dt > 0]
    med = float(np.median(pos)) if len(pos) else 0.0
    gaps = np.nonzero(dt > max(gap_factor * med, 1e-9))[0] if med > 0 else np.array([], int)
    if len(gaps) > 500:  # a sparse, irregular series: do not break it
        gaps = np.array([], int)
    bounds = np.concatenate([[0], gaps + 1, [len(t)]])
    pieces_t, pieces_y = [], []
    n_total = len(t)
    for a, b in zip(bounds[:-1], bounds[1:]):
        st, sy = t[a:b], y[a:b]
        nb = max(1, int(round(buckets * (b - a) / n_total)))
        if len(st) > 2 * nb + 2:
            k = int(math.ceil(len(st) / nb))
            nfull = (len(st) // k) * k
            blk = sy[:nfull].reshape(-1, k)
            base = np.arange(blk.shape[0]) * k
            idx = np.concatenate([base + np.argmin(blk, axis=1), base + np.argmax(blk, axis=1),
                                  np.arange(nfull, len(st)), [0, len(st) - 1]])
            idx = np.unique(idx)
            st, sy = st[idx], sy[idx]
        if pieces_t:
            pieces_t.append([np.nan]); pieces_y.append([np.nan])
        pieces_t.append(st); pieces_y.append(sy)
    return np.concatenate(pieces_t), np.concatenate(pieces_y)


def decimate_path(x, y, ok, buckets=DRAW_BUCKETS):
    """Indices (in time order) of the rows to draw of the curve (x(t), y(t)) where `ok`: all rows
    if few, else per bucket of rows its first one and those with the min and max of x and of y, so
    the turning points (a withdrawal's end, a stall) survive."""
    sel = np.nonzero(ok)[0]
    if len(sel) <= 2 * buckets:
        return sel
    k = int(math.ceil(len(sel) / buckets))
    nfull = (len(sel) // k) * k
    base = np.arange(nfull // k) * k
    keep = [sel[::k], sel[nfull:], sel[-1:]]
    for arr in (x[sel], y[sel]):
        blk = arr[:nfull].reshape(-1, k)
        keep += [sel[base + np.argmin(blk, axis=1)], sel[base + np.argmax(blk, axis=1)]]
    return np.unique(np.concatenate(keep))


def step_changes(t, y):
    """A 0/1 (or small-integer) series reduced to its change points, exact for a 'post' step plot."""
    ok = ~np.isnan(y)
    t, y = t[ok], y[ok]
    if len(t) == 0:
        return t, y
    keep = np.concatenate([[True], y[1:] != y[:-1]])
    keep[-1] = True
    return t[keep], y[keep]


def nanmax_or(v, default=0.0):
    v = v[~np.isnan(v)] if len(v) else v
    return float(np.max(v)) if len(v) else default


def alarm_label(kind):
    return ALARM_STYLE.get(kind, (kind.replace("_", " "), OI["grey"], 0.25, "..", "v"))


def run_span(data):
    """First and last time over the three time series."""
    series = [data["recording"]["time_s"], data["world"]["time_s"], data["firmware"]["time_s"]]
    return float(min(t[0] for t in series)), float(max(t[-1] for t in series))


def shade_alarms(ax, alarms, t_start, t_end, label_text=True):
    """Shade alarm periods (an alarm not cleared runs to the end); returns legend handles."""
    handles = {}
    kinds_order = list(ALARM_STYLE) + sorted({a["kind"] for a in alarms} - set(ALARM_STYLE))
    min_gap = 0.12 * max(t_end - t_start, 1e-9)  # no second label this close (same kind)
    last_label = {}
    for a in sorted(alarms, key=lambda a: a["raised_s"]):
        label, colour, alpha, hatch, _ = alarm_label(a["kind"])
        end = a["cleared_s"] if a["cleared_s"] is not None else t_end
        ax.axvspan(a["raised_s"], max(end, a["raised_s"]), facecolor=matplotlib.colors.to_rgba(colour, alpha),
                   hatch=hatch, edgecolor=matplotlib.colors.to_rgba(colour, 0.35) if hatch else "none",
                   linewidth=0, zorder=0)
        if label_text and a["raised_s"] - last_label.get(a["kind"], -math.inf) >= min_gap:
            last_label[a["kind"]] = a["raised_s"]
            row = kinds_order.index(a["kind"]) if a["kind"] in kinds_order else 0
            txt = label + ("" if a["cleared_s"] is not None else " (not cleared)")
            late = a["raised_s"] > t_start + 0.75 * (t_end - t_start)  # keep the text inside the axes
            ax.text(min(end, t_end) if late else a["raised_s"], 0.985 - 0.075 * row,
                    (txt + " ") if late else (" " + txt), transform=ax.get_xaxis_transform(),
                    ha="right" if late else "left", va="top", fontsize=7.5, color="#333333", zorder=5, clip_on=True,
                    bbox=dict(boxstyle="square,pad=0.1", fc=_lighten(colour, 0.72), ec="none", alpha=0.9))
        if a["kind"] not in handles:
            handles[a["kind"]] = Patch(facecolor=matplotlib.colors.to_rgba(colour, alpha), hatch=hatch,
                                       edgecolor=matplotlib.colors.to_rgba(colour, 0.35) if hatch else "none",
                                       linewidth=0, label=label + " alarm")
    return [handles[k] for k in kinds_order if k in handles]


def save(fig, path):
    """Writes PATH.part and renames it to PATH: a PNG under its name is always complete."""
    part = path + ".part"
    try:
        fig.savefig(part, dpi=DPI, format="png")
        os.replace(part, path)
    except OSError as e:
        raise OutputError(f"{path}: cannot write: {e.strerror or e}")
    finally:
        plt.close(fig)


class OutputError(Exception):
    """An output that cannot be written (exit 3)."""


# ---------------------------------------------------------------------------------------------
# forces.png
def plot_forces(data, path):
    rec, world, fw, alarms = data["recording"], data["world"], data["firmware"], data["alarms"]
    t_start, t_end = run_span(data)
    fig, (ax, axt) = plt.subplots(2, 1, figsize=(11, 7.5), sharex=True, gridspec_kw={"height_ratios": [2.3, 1]},
                                  layout="constrained")
    alarm_handles = shade_alarms(ax, alarms, t_start, t_end)
    shade_alarms(axt, alarms, t_start, t_end, label_text=False)

    hf = rec["handle_force_N"]
    tr, yr = decimate(rec["time_s"], hf)
    ax.plot(tr, yr, color=OI["blue"], lw=0.8, alpha=0.9,
            label=f"handle force, measured (peak {nanmax_or(np.abs(hf)):.2f} N)")
    ax.plot(*decimate(world["time_s"], world["handle_force_N"]), color=OI["black"], lw=0.8,
            label=f"handle force, true (peak {nanmax_or(np.abs(world['handle_force_N'])):.2f} N)")
    tip_meas = np.sqrt(rec["tip_force_x_N"] ** 2 + rec["tip_force_y_N"] ** 2 + rec["tip_force_z_N"] ** 2)
    tm, ym = decimate(rec["time_s"], tip_meas, gap_factor=math.inf)
    ax.plot(tm, ym, ls="none", marker=".", ms=2.2, color=OI["purple"], alpha=0.6,
            label=f"tip force sensor |F| (peak {nanmax_or(tip_meas):.2f} N)")
    est = np.hypot(fw["station_0_normal_N"], fw["station_0_tangential_N"])
    te, ye = decimate(fw["time_s"], est)
    ax.plot(te, ye, color=OI["vermillion"], lw=1.4,
            label=f"tip contact force, estimated by the box (peak {nanmax_or(est):.2f} N)")
    tt, yt = decimate(world["time_s"], world["tip_contact_force_N"])
    ax.plot(tt, yt, color=OI["green"], lw=1.6, ls="--",
            label=f"tip contact force, true (peak {nanmax_or(world['tip_contact_force_N']):.2f} N)")
    ax.axhline(0.0, color="#777777", lw=0.6, zorder=0.5)
    ax.set_ylabel("force (N)")
    ax.set_title("Forces: handle and tip (estimated by the box vs the simulated truth)")
    ymax = max(nanmax_or(hf), nanmax_or(world["handle_force_N"]), nanmax_or(est), nanmax_or(tip_meas),
               nanmax_or(world["tip_contact_force_N"]), 1.0)
    ymin = min(-nanmax_or(-hf), -nanmax_or(-world["handle_force_N"]), 0.0)
    ax.set_ylim(ymin - 0.05 * (ymax - ymin), ymax + 0.28 * (ymax - ymin))  # head room for the alarm labels
    h, _ = ax.get_legend_handles_labels()
    ax.legend(handles=h + alarm_handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              frameon=False, borderaxespad=0.0)
    ax.grid(True, lw=0.4, alpha=0.5)

    tq = rec["handle_torque_Nmm"]
    tqt, tqy = decimate(rec["time_s"], tq)
    axt.plot(tqt, tqy, color=OI["blue"], lw=0.8,
             label=f"handle torque, measured (peak {nanmax_or(np.abs(tq)):.1f} N·mm)")
    axt.plot(*decimate(world["time_s"], world["handle_torque_Nmm"]), color=OI["black"], lw=0.8,
             label=f"handle torque, true (peak {nanmax_or(np.abs(world['handle_torque_Nmm'])):.1f} N·mm)")
    axt.axhline(0.0, color="#777777", lw=0.6, zorder=0.5)
    axt.set_ylabel("torque (N·mm)")
    axt.set_xlabel("time (s)")
    axt.set_title("Handle torque (+ = right-hand about the insertion axis)", fontsize=10)
    axt.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False, borderaxespad=0.0)
    axt.grid(True, lw=0.4, alpha=0.5)
    axt.set_xlim(t_start, t_end if t_end > t_start else t_start + 1.0)
    save(fig, path)


# ---------------------------------------------------------------------------------------------
# advance.png
def plot_advance(data, path):
    rec, world, fw, alarms = data["recording"], data["world"], data["firmware"], data["alarms"]
    t_start, t_end = run_span(data)
    fig = plt.figure(figsize=(10, 10.5), layout="constrained")
    gs = fig.add_gridspec(2, 1, height_ratios=[2.6, 1])
    ax = fig.add_subplot(gs[0])
    axe = fig.add_subplot(gs[1])

    tw, dw, pw = world["time_s"], world["insertion_depth_mm"], world["tip_path_mm"]
    okw = ~np.isnan(dw) & ~np.isnan(pw)
    # the box's view: its tip path against the measured handle depth at the same time
    ti, di = rec["time_s"], rec["insertion_mm"]
    oki = ~np.isnan(di)
    est_label = "tip path estimated by the box (vs the measured depth)"
    if np.count_nonzero(oki) >= 1:
        d_fw = np.interp(fw["time_s"], ti[oki], di[oki])
    elif np.count_nonzero(okw) >= 1:  # no insertion sensor data: against the true depth
        d_fw = np.interp(fw["time_s"], tw[okw], dw[okw])
        est_label = "tip path estimated by the box (vs the true depth: no insertion_mm data)"
    else:
        d_fw = np.full(len(fw["time_s"]), np.nan)
    p_fw = fw["tip_path_mm"]
    okf = ~np.isnan(d_fw) & ~np.isnan(p_fw)
    xs = np.concatenate([dw[okw], d_fw[okf]])
    ys = np.concatenate([pw[okw], p_fw[okf]])
    lo = min(0.0, float(np.min(xs)) if len(xs) else 0.0, float(np.min(ys)) if len(ys) else 0.0)
    hi = max(float(np.max(xs)) if len(xs) else 1.0, float(np.max(ys)) if len(ys) else 1.0, 1.0)
    pad = 0.06 * (hi - lo)
    ax.plot([lo - pad, hi + pad], [lo - pad, hi + pad], color="#888888", lw=1.0, ls=":",
            label="tip follows the handle (45° line)")
    ax.fill_between([lo - pad, hi + pad], [lo - pad, lo - pad], [lo - pad, hi + pad], color="#f1f3f7", lw=0,
                    zorder=0, label="tip lags the handle (slack: a loop or compression)")
    sel = decimate_path(d_fw, p_fw, okf)
    ax.plot(d_fw[sel], p_fw[sel], color=OI["vermillion"], lw=1.3, label=est_label)
    sel = decimate_path(dw, pw, okw)
    ax.plot(dw[sel], pw[sel], color=OI["green"], lw=2.0, ls="--", label="tip path, true (simulation)")
    # time marks along the true curve
    if np.count_nonzero(okw) >= 2:
        span = tw[okw][-1] - tw[okw][0]
        step = next((s for s in (1, 2, 5, 10, 20, 30, 60, 120, 300, 600, 1200, 3600) if span / s <= 8), 3600)
        marks = np.arange(math.ceil(tw[okw][0] / step) * step, tw[okw][-1] + 1e-9, step)
        mx = np.interp(marks, tw[okw], dw[okw]); my = np.interp(marks, tw[okw], pw[okw])
        ax.plot(mx, my, ls="none", marker="|", ms=7, color=OI["green"], mew=1.2)
        for x, y, m in zip(mx, my, marks):
            ax.annotate(f"{m:g} s", (x, y), xytext=(4, -9), textcoords="offset points", fontsize=7,
                        color="#2d6b55")
    # alarm markers on the true curve; the times go into the legend (text next to markers that
    # sit close together in the loop would overlap)
    events = {}
    for a in alarms:
        for key in ("raised_s", "cleared_s"):
            if a[key] is not None:
                events.setdefault((a["kind"], key), []).append(a[key])
    order = list(ALARM_STYLE) + sorted({a["kind"] for a in alarms} - set(ALARM_STYLE))
    for kind in order:
        label, colour, _, _, marker = alarm_label(kind)
        for key, filled in (("raised_s", True), ("cleared_s", False)):
            times = events.get((kind, key))
            if not times or np.count_nonzero(okw) == 0:
                continue
            x = np.interp(times, tw[okw], dw[okw]); y = np.interp(times, tw[okw], pw[okw])
            shown = ", ".join(f"{t:.1f}" for t in times[:4]) + (", …" if len(times) > 4 else "")
            ax.plot(x, y, ls="none", marker=marker, ms=9, mec=_darken(colour), mew=1.6,
                    mfc=colour if filled else "white", zorder=6,
                    label=f"{label} alarm {'raised' if filled else 'cleared'} (t = {shown} s)")
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_ylim(lo - pad, hi + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("handle insertion depth (mm past the anus)")
    ax.set_ylabel("tip position along the colon centerline (mm from the anus)")
    ax.set_title("Tip advance vs handle advance (below the 45° line: the scope loops or compresses)")
    ax.grid(True, lw=0.4, alpha=0.5)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)

    # efficiency and self-lock over time
    eff = fw["advance_efficiency"]
    te, ye = decimate(fw["time_s"], eff)
    axe.axhline(1.0, color="#888888", lw=0.8, ls=":")
    axe.axhline(0.0, color="#888888", lw=0.6)
    lo_e = min(-0.1, -nanmax_or(-eff, 0.0))
    hi_e = max(1.15, nanmax_or(eff, 1.0))
    clipped = ""
    if lo_e < -2.0 or hi_e > 3.0:  # spikes while the handle barely moves: say so, do not hide them
        clipped = f"; off the axis: {lo_e:.3g} .. {hi_e:.3g}"
    axe.plot(te, ye, color=OI["vermillion"], lw=1.0, label=f"advance efficiency (box{clipped})")
    axe.set_ylim(max(lo_e, -2.0) - 0.05, min(hi_e, 3.0) + 0.05)
    axe.set_ylabel("advance efficiency\n(tip advance / handle advance)")
    axe.set_xlabel("time (s)")
    axe.grid(True, lw=0.4, alpha=0.5)
    axs = axe.twinx()
    ts, ys = step_changes(fw["time_s"], fw["self_lock_alarm"])
    if len(ts):
        ts = np.append(ts, t_end); ys = np.append(ys, ys[-1])
    _, sl_colour, sl_alpha, sl_hatch, _ = alarm_label("self_lock")
    axs.fill_between(ts, 0, ys, step="post", facecolor=matplotlib.colors.to_rgba(sl_colour, sl_alpha),
                     hatch=sl_hatch, edgecolor=matplotlib.colors.to_rgba(sl_colour, 0.35), lw=0)
    axs.step(ts, ys, where="post", color=sl_colour, lw=1.6, label="self-lock alarm (box)")
    axs.set_ylim(-0.05, 2.1)
    axs.set_yticks([0, 1], ["off", "on"])
    axs.set_ylabel("self-lock alarm", color=sl_colour)
    axs.tick_params(axis="y", colors=sl_colour)
    h1, l1 = axe.get_legend_handles_labels()
    h2, l2 = axs.get_legend_handles_labels()
    axe.legend(h1 + h2, l1 + l2, loc="upper right", fontsize=8, framealpha=0.9)
    axe.set_title("Advance efficiency and the self-lock alarm over time", fontsize=10)
    axe.set_xlim(t_start, t_end if t_end > t_start else t_start + 1.0)
    save(fig, path)


def _darken(colour, amount=0.35):
    c = np.array(matplotlib.colors.to_rgb(colour))
    return tuple(c * (1.0 - amount))


# ---------------------------------------------------------------------------------------------
# snapshots.png
def resample_tube(points, radius, region, max_step):
    """Points every <= max_step mm along a polyline, with the radius interpolated and the region of
    the segment they lie on."""
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    n_sub = np.maximum(1, np.ceil(seg / max_step).astype(int))
    seg_idx = np.repeat(np.arange(len(seg)), n_sub)
    frac = np.concatenate([np.arange(n) / n for n in n_sub])
    p = points[seg_idx] + frac[:, None] * (points[seg_idx + 1] - points[seg_idx])
    r = radius[seg_idx] + frac * (radius[seg_idx + 1] - radius[seg_idx])
    p = np.vstack([p, points[-1]])
    r = np.append(r, radius[-1])
    reg = [region[i] for i in seg_idx] + [region[-1]]
    return p, r, reg


def draw_tube(ax, points, radius, colours, outline, outline_mm, zorder):
    """The lumen in projection: the union of discs of the inner radius around the centerline (exact
    for a tube), with an outline from slightly larger discs drawn underneath."""
    xy = points[:, :2]
    if outline is not None:
        d = 2.0 * (radius + outline_mm)
        ax.add_collection(EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=xy,
                                            offset_transform=ax.transData, facecolors=outline,
                                            edgecolors="none", zorder=zorder))
    d = 2.0 * radius
    ax.add_collection(EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=xy,
                                        offset_transform=ax.transData, facecolors=colours,
                                        edgecolors="none", zorder=zorder + 0.1))


def point_at_path(colon_mm, path_mm):
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(colon_mm, axis=0), axis=1))])
    return np.column_stack([np.interp(path_mm, arc, colon_mm[:, k]) for k in range(3)])


def choose_snapshots(snaps):
    if len(snaps) <= MAX_SNAPSHOT_PANELS:
        return snaps
    idx = np.unique(np.round(np.linspace(0, len(snaps) - 1, MAX_SNAPSHOT_PANELS)).astype(int))
    return [snaps[i] for i in idx]


def plot_snapshots(data, path):
    colon, snaps_all = data["colon"], data["snapshots"]
    snaps = choose_snapshots(snaps_all)
    n = len(snaps)
    ncols = {0: 1, 1: 1, 2: 2, 3: 3, 4: 2}.get(n, 3)
    nrows = max(1, int(math.ceil(max(n, 1) / ncols)))
    cl, radius, region = colon["centerline"], colon["radius"], colon["region"]

    # shared extent (frontal view: x to the patient's left, y cranial) and force scale
    allpts = [cl] + [s["colon_mm"] for s in snaps] + [s["scope_mm"] for s in snaps if len(s["scope_mm"])]
    allxy = np.vstack([p[:, :2] for p in allpts])
    rmax = float(np.max(radius))
    x0, y0 = allxy.min(axis=0) - rmax - 10.0
    x1, y1 = allxy.max(axis=0) + rmax + 10.0
    fmax = 0.0
    for s in snaps:
        if len(s["contact_force"]):
            fmax = max(fmax, float(np.max(np.linalg.norm(s["contact_force"], axis=1))))
        if len(s["est_force"]):
            fmax = max(fmax, float(np.max(s["est_force"])))
    fmax = fmax if fmax > 0 else 1.0
    norm = matplotlib.colors.Normalize(vmin=0.0, vmax=fmax)
    cmap = plt.get_cmap(FORCE_CMAP)
    arrow_mm_per_N = 0.14 * max(x1 - x0, y1 - y0) / fmax  # the largest force: 14 % of the view

    region_colour = {r: _lighten(REGION_BASE.get(r, OI["grey"]), 0.62) for r in set(region)}
    present = [r for r in REGIONS if r in set(region)] + sorted(set(region) - set(REGIONS))
    handles = [Patch(facecolor=region_colour[r], edgecolor="#7a7a7a", label=r.replace("_", " ")) for r in present]
    handles += [Line2D([], [], color="#9a9a9a", lw=0.8, ls=(0, (4, 3)), label="colon at rest (centerline; faint lumen)"),
                Line2D([], [], color="#555555", lw=0.7, label="colon now (centerline; coloured lumen)"),
                Line2D([], [], color="#1a1a1a", lw=3.2, label="scope"),
                Line2D([], [], ls="none", marker="o", ms=6.5, mfc="white", mec="#1a1a1a", mew=1.8, label="tip"),
                Line2D([], [], ls="none", marker=r"$\rightarrow$", ms=12, color="#333333", label="true wall force (arrow, dot)"),
                Line2D([], [], ls="none", marker="D", ms=6, mfc=cmap(0.6), mec="black", label="estimated station force")]
    legend_ncol = {1: 2, 2: 4}.get(ncols, 7)
    legend_h = 0.19 * math.ceil(len(handles) / legend_ncol) + 0.1  # inches

    panel_w = {1: 6.0, 2: 5.2}.get(ncols, 4.6)  # inches
    panel_h = panel_w * min(max((y1 - y0) / max(x1 - x0, 1e-9), 0.4), 2.5) * 0.92 + 0.45
    fig = plt.figure(figsize=(panel_w * ncols + 1.2, panel_h * nrows + legend_h + 0.4), layout="constrained")
    gs = fig.add_gridspec(nrows + 1, ncols, height_ratios=[panel_h] * nrows + [legend_h])
    axes = np.empty((nrows, ncols), dtype=object)
    for r in range(nrows):
        for c in range(ncols):
            axes[r, c] = fig.add_subplot(gs[r, c], sharex=axes[0, 0] if (r or c) else None,
                                         sharey=axes[0, 0] if (r or c) else None)
    lax = fig.add_subplot(gs[nrows, :])
    lax.axis("off")
    rest_p, rest_r, rest_reg = resample_tube(cl, radius, region, max_step=max(1.0, 0.25 * float(np.min(radius))))
    for i, ax in enumerate(axes.flat):
        if i >= n:
            if n:  # an unused grid cell (with no snapshot at all, the first shows the colon at rest)
                ax.set_visible(False)
            continue
        s = snaps[i]
        # at-rest colon, faint
        draw_tube(ax, rest_p, rest_r, "#f3f3f3", "#d4d4d4", 1.0, zorder=1)
        # displaced colon, solid, regions coloured
        dp, dr, dreg = resample_tube(s["colon_mm"], radius, region, max_step=max(1.0, 0.25 * float(np.min(radius))))
        draw_tube(ax, dp, dr, [region_colour[r] for r in dreg], "#7a7a7a", 1.2, zorder=2)
        ax.plot(cl[:, 0], cl[:, 1], color="#9a9a9a", lw=0.8, ls=(0, (4, 3)), zorder=3)
        ax.plot(s["colon_mm"][:, 0], s["colon_mm"][:, 1], color="#555555", lw=0.7, zorder=3)
        sc = s["scope_mm"]
        if len(sc):
            ax.plot(sc[:, 0], sc[:, 1], color="white", lw=5.2, solid_capstyle="round", zorder=4)
            ax.plot(sc[:, 0], sc[:, 1], color="#1a1a1a", lw=3.2, solid_capstyle="round", zorder=4.1)
            ax.plot(sc[-1, 0], sc[-1, 1], marker="o", ms=6.5, mfc="white", mec="#1a1a1a", mew=1.8, zorder=4.2)
        # true contacts: arrows ending at the contact point (the wall pushing), coloured by |F|
        cp, cf = s["contact_pos"], s["contact_force"]
        if len(cp):
            mag = np.linalg.norm(cf, axis=1)
            order = np.argsort(mag)
            cp, cf, mag = cp[order], cf[order], mag[order]
            u, v = cf[:, 0] * arrow_mm_per_N, cf[:, 1] * arrow_mm_per_N
            ax.quiver(cp[:, 0] - u, cp[:, 1] - v, u, v, mag, cmap=cmap, norm=norm, angles="xy",
                      scale_units="xy", scale=1.0, width=0.011, headwidth=3.2, headlength=3.6,
                      headaxislength=3.2, edgecolor="black", linewidth=0.5, zorder=5)
            ax.scatter(cp[:, 0], cp[:, 1], c=mag, cmap=cmap, norm=norm, s=22, edgecolors="black",
                       linewidths=0.6, zorder=5.5)
        # the box's estimate: a diamond per station, at its path position on the displaced colon
        if len(s["est_path"]):
            ep = point_at_path(s["colon_mm"], s["est_path"])
            ax.scatter(ep[:, 0], ep[:, 1], c=s["est_force"], cmap=cmap, norm=norm, marker="D", s=34,
                       edgecolors="white", linewidths=1.0, zorder=6)
            ax.scatter(ep[:, 0], ep[:, 1], facecolors="none", marker="D", s=58,
                       edgecolors="black", linewidths=0.7, zorder=6.1)
        ax.set_title(f"{s['label']}\nt = {s['time_s']:.2f} s", fontsize=9.5)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, lw=0.3, alpha=0.4)
        ax.tick_params(labelsize=8)
    # axes are shared: tick labels only on the outer panels (the lowest used one in each column)
    for i, ax in enumerate(axes.flat):
        r, c = divmod(i, ncols)
        lowest = i + ncols >= max(n, 1)
        ax.tick_params(labelbottom=lowest, labelleft=(c == 0))
        if lowest:
            ax.set_xlabel("x (mm, + = patient's left)", fontsize=8.5)
        if c == 0:
            ax.set_ylabel("y (mm, + = cranial)", fontsize=8.5)
    if n == 0:
        ax = axes[0, 0]
        draw_tube(ax, rest_p, rest_r, [region_colour[r] for r in rest_reg], "#7a7a7a", 1.2, zorder=2)
        ax.plot(cl[:, 0], cl[:, 1], color="#555555", lw=0.7, zorder=3)
        ax.set_xlim(x0, x1); ax.set_ylim(y0, y1); ax.set_aspect("equal", adjustable="box")
        ax.set_title("no snapshots in snapshots.json (the colon at rest)", fontsize=10)
        ax.set_xlabel("x (mm, + = patient's left)"); ax.set_ylabel("y (mm, + = cranial)")
    sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=axes.ravel().tolist(), shrink=0.8, aspect=30, pad=0.01,
                 label="contact force |F| (N): true (arrows, dots) and estimated (diamonds)")
    extra = f" ({n} of {len(snaps_all)})" if len(snaps_all) > n else ""
    fig.suptitle(f"Snapshots{extra}: frontal view (looking at the patient: x to the patient's left, y cranial)",
                 fontsize=11)
    lax.legend(handles=handles, loc="center", ncol=legend_ncol, fontsize=8, frameon=False)
    save(fig, path)


# ---------------------------------------------------------------------------------------------
def main(argv=None):
    ap = argparse.ArgumentParser(
        prog="plot_run.py",
        description="Plot a simulated run: writes forces.png, advance.png and snapshots.png into RUN_DIR.",
        epilog="Inputs in RUN_DIR: recording.csv, world.csv, firmware.csv, snapshots.json, summary.json "
               "(schema: host_sim/plots/README.md). Exit status: 0 ok, 2 bad usage or a missing/malformed "
               "input, 3 an output that cannot be written.")
    ap.add_argument("run_dir", metavar="RUN_DIR", help="directory of the run (inputs and outputs)")
    ap.add_argument("--quiet", action="store_true", help="print nothing on success")
    ap.add_argument("--summary", metavar="FILE",
                    help="read the summary from FILE instead of RUN_DIR/summary.json (scopekin demo draws the "
                         "plots before it renames summary.json.part, last of all)")
    args = ap.parse_args(argv)
    try:
        data = read_run(args.run_dir, args.summary)
        for name, fn in (("forces.png", plot_forces), ("advance.png", plot_advance), ("snapshots.png", plot_snapshots)):
            out = os.path.join(args.run_dir, name)
            t0 = time.monotonic()
            fn(data, out)
            if not args.quiet:
                print(f"plot_run: wrote {out} ({os.path.getsize(out)} bytes, {time.monotonic() - t0:.2f} s)")
    except InputError as e:
        sys.stderr.write(f"plot_run: {e}\n")
        return 2
    except OutputError as e:
        sys.stderr.write(f"plot_run: {e}\n")
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
