#!/usr/bin/python3
"""Write a plausible synthetic simulated run for host_sim/plots/plot_run.py.

Usage: make_sample_run.py OUT_DIR [--duration-s T] [--seed N]

OUT_DIR (created if missing) receives recording.csv, world.csv, firmware.csv, snapshots.json and
summary.json in the schema of host_sim/plots/README.md (all the columns, not only those plot_run.py
reads); a previous run's files there, and its forces.png, advance.png and snapshots.png, are removed
first. The story
(times for the default 40 s; another --duration-s stretches it, same geometry): the scope is
advanced at 30 mm/s through the rectum and the sigmoid; from ~13 s the tip stalls near the
sigmoid-descending junction and the sigmoid bulges cranially into a loop; the self-lock alarm and
the contact-force warning and critical alarms are raised; the operator withdraws 150 mm (21-26 s),
the loop shrinks and the alarms clear; after a twist (26-27 s) the re-advance carries the tip
through the descending colon to the splenic flexure.
The numbers are invented (shapes, not physics); the centerline is the bundled default colon's
waypoints (model/colon/bundled_colons.cpp) through a Catmull-Rom spline.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

REGIONS = ["rectum", "sigmoid", "descending", "splenic_flexure", "transverse", "hepatic_flexure",
           "ascending", "cecum"]

# (position mm, inner radius mm, region of the stretch starting here)
WAYPOINTS = [
    ((0, 0, 0), 18.0, "rectum"), ((0, 60, -25), 18.0, "rectum"), ((5, 120, -35), 17.0, "rectum"),
    ((10, 150, -25), 15.0, "sigmoid"), ((-30, 185, 10), 14.0, "sigmoid"), ((-60, 222, 40), 14.0, "sigmoid"),
    ((-60, 272, 65), 14.0, "sigmoid"), ((-10, 298, 75), 14.0, "sigmoid"), ((45, 288, 55), 14.0, "sigmoid"),
    ((90, 270, 25), 13.0, "sigmoid"), ((115, 255, -10), 12.5, "descending"),
    ((125, 340, -25), 15.0, "descending"), ((130, 430, -30), 15.0, "descending"),
    ((128, 500, -25), 17.0, "splenic_flexure"), ((110, 545, -5), 19.0, "splenic_flexure"),
    ((75, 555, 20), 22.0, "transverse"), ((25, 470, 60), 22.0, "transverse"), ((-40, 385, 75), 22.0, "transverse"),
    ((-110, 430, 60), 22.0, "transverse"), ((-160, 525, 25), 22.0, "hepatic_flexure"),
    ((-185, 510, 0), 23.0, "hepatic_flexure"), ((-190, 475, -15), 23.0, "ascending"),
    ((-190, 400, -20), 23.0, "ascending"), ((-185, 330, -20), 24.0, "cecum"), ((-180, 285, -15), 24.0, "cecum"),
]

RUN_FILES = ["recording.csv", "world.csv", "firmware.csv", "snapshots.json", "summary.json"]
N_STATIONS = 12
SCOPE_LENGTH_MM = 1700.0
STATION_SPACING_MM = 45.0
BASE_T = 40.0  # the story's length in s; everything is written in these "story seconds"


# ---------------------------------------------------------------------------------------------
# colon geometry
def make_colon(spacing_mm=10.0):
    pts = np.array([w[0] for w in WAYPOINTS], float)
    rad = np.array([w[1] for w in WAYPOINTS], float)
    # uniform Catmull-Rom, end points duplicated
    ext = np.vstack([pts[0], pts, pts[-1]])
    dense, dense_r, dense_seg = [], [], []
    for i in range(len(pts) - 1):
        p0, p1, p2, p3 = ext[i], ext[i + 1], ext[i + 2], ext[i + 3]
        for u in np.linspace(0.0, 1.0, 40, endpoint=False):
            u2, u3 = u * u, u * u * u
            p = 0.5 * ((2 * p1) + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u2 + (-p0 + 3 * p1 - 3 * p2 + p3) * u3)
            dense.append(p)
            dense_r.append(rad[i] + (rad[i + 1] - rad[i]) * u)
            dense_seg.append(i)
    dense.append(pts[-1]); dense_r.append(rad[-1]); dense_seg.append(len(pts) - 2)
    dense = np.array(dense); dense_r = np.array(dense_r); dense_seg = np.array(dense_seg)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(dense, axis=0), axis=1))])
    n = int(math.ceil(s[-1] / spacing_mm)) + 1
    si = np.linspace(0.0, s[-1], n)
    centerline = np.column_stack([np.interp(si, s, dense[:, k]) for k in range(3)])
    radius = np.interp(si, s, dense_r)
    seg = dense_seg[np.clip(np.searchsorted(s, si, side="right") - 1, 0, len(dense_seg) - 1)]
    region = [WAYPOINTS[j][2] for j in seg]
    return centerline, radius, region, si


class Colon:
    def __init__(self):
        self.c0, self.radius, self.region, self.s = make_colon()
        sig = [i for i, r in enumerate(self.region) if r == "sigmoid"]
        self.sig0, self.sig1 = self.s[sig[0]], self.s[sig[-1]]
        self.bulge_dir = np.array([-0.45, 1.0, 0.35]) / np.linalg.norm([-0.45, 1.0, 0.35])

    def displaced(self, tip_path, slack):
        """Centerline with the sigmoid bulged so that its length between the sigmoid start and the
        tip grows by `slack` (the loop the handle pushed in without the tip moving)."""
        a = self.sig0 + 20.0
        b = min(self.sig1, tip_path - 25.0)
        if slack <= 0.5 or b - a < 60.0:
            return self.c0.copy(), 0.0
        w = np.where((self.s > a) & (self.s < b), np.sin(np.pi * (self.s - a) / (b - a)) ** 2, 0.0)
        base = self._length(self.c0, a, b)

        def extra(amp):
            return self._length(self.c0 + amp * w[:, None] * self.bulge_dir, a, b) - base

        lo, hi = 0.0, 10.0
        while extra(hi) < slack and hi < 2000:
            hi *= 2
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if extra(mid) < slack else (lo, mid)
        amp = 0.5 * (lo + hi)
        return self.c0 + amp * w[:, None] * self.bulge_dir, amp

    def _length(self, c, a, b):
        m = (self.s >= a - 1e-9) & (self.s <= b + 1e-9)
        q = c[m]
        return float(np.sum(np.linalg.norm(np.diff(q, axis=0), axis=1)))

    def point_at(self, c, path_mm):
        return np.array([np.interp(path_mm, self.s, c[:, k]) for k in range(3)])

    def tangent_at(self, c, path_mm):
        d = self.point_at(c, min(path_mm + 5.0, self.s[-1])) - self.point_at(c, max(path_mm - 5.0, 0.0))
        return d / max(np.linalg.norm(d), 1e-9)

    def region_at(self, path_mm):
        i = int(np.clip(np.searchsorted(self.s, path_mm, side="right") - 1, 0, len(self.s) - 1))
        return self.region[i]

    def scope_nodes(self, c, tip_path, spacing=10.0):
        """The inserted scope: along the displaced centerline from the anus to the tip, equally spaced
        in true (displaced) arc length; node 0 at the anus, last = tip."""
        m = self.s <= tip_path
        pts = np.vstack([c[m], self.point_at(c, tip_path)])
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        n = max(2, int(math.ceil(arc[-1] / spacing)) + 1)
        a = np.linspace(0.0, arc[-1], n)
        return np.column_stack([np.interp(a, arc, pts[:, k]) for k in range(3)])


def quat_from_z_to(v):
    """Unit quaternion (w, x, y, z) rotating +z onto direction v."""
    z = np.array([0.0, 0.0, 1.0])
    v = v / max(np.linalg.norm(v), 1e-12)
    d = float(np.dot(z, v))
    if d < -0.999999:
        return (0.0, 1.0, 0.0, 0.0)
    ax = np.cross(z, v)
    q = np.array([1.0 + d, ax[0], ax[1], ax[2]])
    q /= np.linalg.norm(q)
    return tuple(q)


# ---------------------------------------------------------------------------------------------
# the story, in story seconds u (0..30)
def insertion_at(u):
    """Prescribed handle depth (mm) and whether the handle is advancing (+1), withdrawing (-1)."""
    if u < 1.0:
        return 20.0, 0
    if u < 21.0:
        return 20.0 + 30.0 * (u - 1.0), +1
    if u < 26.0:
        return 620.0 - 30.0 * (u - 21.0), -1
    if u < 27.0:
        return 470.0, 0
    return 470.0 + 30.0 * (u - 27.0), +1


def efficiency_at(u):
    if u < 13.0:
        return 0.96
    if u < 17.0:
        return 0.96 - (0.96 - 0.08) * (u - 13.0) / 4.0
    if u < 21.0:
        return 0.08
    if u < 33.0:
        return 1.03  # the remaining loop straightens while advancing
    return 0.96


def integrate_story(du):
    """Handle depth, true tip path and slack (loop length) at story times 0, du, 2 du, ..."""
    u = np.arange(0.0, BASE_T + 0.5 * du, du)
    ins = np.empty_like(u); tip = np.empty_like(u); mode = np.empty_like(u)
    tip_now = 18.0
    prev_ins = None
    for i, ui in enumerate(u):
        d, m = insertion_at(ui)
        if prev_ins is not None:
            dd = d - prev_ins
            if dd > 0:
                tip_now += efficiency_at(ui) * dd
            elif dd < 0:
                slack = prev_ins - tip_now
                if slack > 30.0:
                    tip_now += 0.08 * (-dd)  # paradoxical advance while the loop is reduced
                else:
                    tip_now += dd
        tip_now = min(tip_now, d - 2.0)
        ins[i], tip[i], mode[i] = d, tip_now, m
        prev_ins = d
    return u, ins, tip, ins - tip, mode


def smooth_bump(u, centre, width):
    return np.exp(-0.5 * ((u - centre) / width) ** 2)


# ---------------------------------------------------------------------------------------------
def fmt_col(values, fmt):
    return ["" if (v is None or (isinstance(v, float) and v != v)) else fmt % v for v in values]


def write_csv(path, header, columns):
    n = len(columns[0])
    with open(path, "w", newline="") as f:
        f.write(",".join(header) + "\n")
        lines = [",".join(row) for row in zip(*columns)]
        f.write("\n".join(lines))
        f.write("\n")
    assert all(len(c) == n for c in columns)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir")
    ap.add_argument("--duration-s", type=float, default=40.0, help="run length (default 40 s = 40k recording rows)")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args(argv)
    T = args.duration_s
    if not (T >= 1.0):
        ap.error("--duration-s must be >= 1")
    k = T / BASE_T  # real s per story s
    rng = np.random.default_rng(args.seed)
    os.makedirs(args.out_dir, exist_ok=True)
    for stale in RUN_FILES + ["forces.png", "advance.png", "snapshots.png"]:  # a previous run's files
        try:
            os.remove(os.path.join(args.out_dir, stale))
        except FileNotFoundError:
            pass
    colon = Colon()

    # -- fine story integration and derived truths, on a 1 ms grid in real time --------------
    n_ms = int(round(T * 1000.0)) + 1
    t_ms = np.arange(n_ms) / 1000.0
    u_ms = t_ms / k
    su, s_ins, s_tip, s_slack, s_mode = integrate_story(0.005)
    ins_ms = np.interp(u_ms, su, s_ins)
    tip_ms = np.interp(u_ms, su, s_tip)
    slack_ms = np.interp(u_ms, su, s_slack)
    mode_ms = np.interp(u_ms, su, s_mode)
    slack_excess = np.clip(slack_ms - 8.0, 0.0, None)
    handle_true = np.where(mode_ms > 0.5, 1.4 + 0.075 * slack_excess, np.where(mode_ms < -0.5, -1.6 - 0.01 * slack_excess, 0.35))
    handle_true += 0.8 * smooth_bump(u_ms, 4.5, 0.4) + 0.6 * smooth_bump(u_ms, 35.0, 0.8)
    torque_true = 3.0 * np.sin(2 * np.pi * u_ms / 9.0) + 160.0 * ((u_ms > 26.0) & (u_ms < 27.0)) * np.sin(np.pi * np.clip(u_ms - 26.0, 0, 1))
    tip_force_true = 0.25 + 0.03 * slack_excess + 1.2 * smooth_bump(u_ms, 5.0, 0.5) + 0.9 * smooth_bump(u_ms, 37.0, 0.9)
    roll_deg = np.where(u_ms > 26.0, 25.0 * np.clip(u_ms - 26.0, 0, 1), 0.0)

    # -- geometry on a coarse grid ------------------------------------------------------------
    n_geo = int(min(2000, max(300, T * 40)))
    t_geo = np.linspace(0.0, T, n_geo)
    tip_geo = np.interp(t_geo, t_ms, tip_ms); slack_geo = np.interp(t_geo, t_ms, slack_ms)
    geo_tip = np.empty((n_geo, 3)); geo_20 = np.empty((n_geo, 3)); geo_sig = np.empty((n_geo, 3))
    geo_tan_tip = np.empty((n_geo, 3)); geo_tan_20 = np.empty((n_geo, 3))
    sig_mid = 0.5 * (colon.sig0 + colon.sig1)
    entry_axis = (colon.c0[1] - colon.c0[0]) / np.linalg.norm(colon.c0[1] - colon.c0[0])
    for i in range(n_geo):
        c, _ = colon.displaced(tip_geo[i], slack_geo[i])
        nodes = colon.scope_nodes(c, tip_geo[i], spacing=5.0)
        geo_tip[i] = nodes[-1]
        geo_tan_tip[i] = nodes[-1] - nodes[-2]
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(nodes, axis=0), axis=1))])
        a20 = arc[-1] - 200.0  # the EM sensor 200 mm from the tip, outside the body while a20 < 0
        if a20 >= 0.0:
            geo_20[i] = [np.interp(a20, arc, nodes[:, q]) for q in range(3)]
            j = min(int(np.searchsorted(arc, a20)), len(nodes) - 2)
            geo_tan_20[i] = nodes[j + 1] - nodes[j]
        else:
            geo_20[i] = a20 * entry_axis  # a20 < 0: behind the anus on the entry axis
            geo_tan_20[i] = entry_axis
        geo_sig[i] = colon.point_at(c, sig_mid)

    def geo_interp(arr, t):
        return np.column_stack([np.interp(t, t_geo, arr[:, q]) for q in range(3)])

    # -- recording.csv (1 kHz rows) -----------------------------------------------------------
    handle_meas = handle_true + rng.normal(0.0, 0.12, n_ms)
    torque_meas = torque_true + rng.normal(0.0, 1.5, n_ms)
    ins_meas = ins_ms + rng.normal(0.0, 0.15, n_ms)
    ins_meas = np.where(np.arange(n_ms) % 5 == 0, ins_meas, np.nan)  # encoder every 5 ms
    roll_meas = np.where(np.arange(n_ms) % 5 == 0, np.radians(roll_deg), np.nan)
    em_rows = (np.arange(n_ms) % 25 == 0)  # EM tracker 40 Hz
    tf_rows = (np.arange(n_ms) % 10 == 3)  # tip force sensor 100 Hz
    tf_rows &= ~((u_ms > 29.0) & (u_ms < 29.8))  # a dropout
    cols, header = [], []

    def add(name, values, fmt="%.4f"):
        header.append(name)
        cols.append(fmt_col(values.tolist() if isinstance(values, np.ndarray) else values, fmt))

    add("time_s", t_ms, "%.3f")
    add("handle_force_N", handle_meas)
    add("handle_torque_Nmm", torque_meas, "%.3f")
    add("insertion_mm", ins_meas, "%.3f")
    add("roll_rad", roll_meas, "%.5f")
    t_em = t_ms[em_rows]
    sensors = {
        "em_tip": (geo_interp(geo_tip, t_em), geo_interp(geo_tan_tip, t_em)),
        "em_20cm": (geo_interp(geo_20, t_em), geo_interp(geo_tan_20, t_em)),
        # the box at the handle: on the entry axis, (scope length - insertion) outside the anus
        "em_handle": (np.outer(-(SCOPE_LENGTH_MM - np.interp(t_em, t_ms, ins_ms)), entry_axis),
                      np.tile(entry_axis, (len(t_em), 1))),
        "em_sigmoid": (geo_interp(geo_sig, t_em), np.tile([0.0, 0.0, 1.0], (len(t_em), 1))),
    }
    for name, (pos, tan) in sensors.items():
        pos = pos + rng.normal(0.0, 0.4, pos.shape)
        quats = np.array([quat_from_z_to(v) for v in tan])
        for q, ax in enumerate("xyz"):
            full = np.full(n_ms, np.nan); full[em_rows] = pos[:, q]
            add(f"{name}_{ax}_mm", full, "%.2f")
        for q, comp in enumerate(["qw", "qx", "qy", "qz"]):
            full = np.full(n_ms, np.nan); full[em_rows] = quats[:, q]
            add(f"{name}_{comp}", full, "%.5f")
    # measured tip force: magnitude ~ true tip force, a direction that wanders, noise
    ang = 0.7 * np.sin(2 * np.pi * u_ms / 7.0)
    mag = tip_force_true * (1.0 + 0.08 * np.sin(2 * np.pi * u_ms / 3.1)) + rng.normal(0.0, 0.08, n_ms)
    fx = mag * np.cos(ang) * 0.8; fy = mag * np.sin(ang) * 0.8; fz = mag * 0.6
    for name, comp in (("tip_force_x_N", fx), ("tip_force_y_N", fy), ("tip_force_z_N", fz)):
        add(name, np.where(tf_rows, comp, np.nan))
    region_rec = [colon.region_at(p) if e else "" for p, e in zip(tip_ms.tolist(), em_rows.tolist())]
    header.append("region"); cols.append(region_rec)
    add("x_frame_counter", np.arange(n_ms).astype(float), "%.0f")
    write_csv(os.path.join(args.out_dir, "recording.csv"), header, cols)

    # -- world.csv (~30 Hz, rows at the first 10 ms step at or after k/30 s) ---------------------
    n_w = int(math.floor(T * 30.0 + 1e-9)) + 1
    t_w = np.unique(np.ceil(np.arange(n_w) / 30.0 / 0.01 - 1e-9) * 0.01)
    t_w = t_w[t_w <= T + 1e-9] + 0.0  # no -0.000
    idx_w = np.clip(np.round(t_w * 1000.0).astype(int), 0, n_ms - 1)
    tipw = geo_interp(geo_tip, t_w)
    n200 = geo_interp(geo_20, t_w)
    slack_w = slack_ms[idx_w]
    ccount = (3 + slack_w / 12.0 + rng.integers(0, 3, len(t_w))).astype(int)
    fmax = np.maximum(tip_force_true[idx_w], 0.04 * slack_w + 0.3)
    ftot = fmax * (1.0 + 0.45 * ccount)
    cols, header = [], []
    add("time_s", t_w, "%.3f")
    add("handle_force_N", handle_true[idx_w])
    add("handle_torque_Nmm", torque_true[idx_w], "%.3f")
    add("insertion_depth_mm", ins_ms[idx_w], "%.3f")
    add("roll_deg", roll_deg[idx_w], "%.3f")
    for q, ax in enumerate("xyz"):
        add(f"tip_{ax}_mm", tipw[:, q], "%.3f")
    for q, ax in enumerate("xyz"):
        add(f"node_200mm_{ax}_mm", n200[:, q], "%.3f")
    add("contact_count", ccount.astype(float), "%.0f")
    add("contact_force_total_N", ftot)
    add("contact_force_max_N", fmax)
    tip_reg_w = [colon.region_at(p) for p in tip_ms[idx_w].tolist()]
    for r in REGIONS:
        v = np.zeros(len(t_w))
        if r == "rectum":
            v = 0.2 + 0.3 * smooth_bump(u_ms[idx_w], 4.5, 0.5)
        elif r == "sigmoid":
            v = 0.3 + 0.04 * slack_w
        elif r == "descending":
            v = np.where(tip_ms[idx_w] > colon.sig1, tip_force_true[idx_w], 0.0)
        add(f"max_contact_force_{r}_N", v)
    stick = (ccount * np.where(slack_w > 40, 0.7, 0.3)).astype(int)
    add("sticking_contacts", stick.astype(float), "%.0f")
    add("slipping_contacts", (ccount - stick).astype(float), "%.0f")
    add("tip_driving_angle_deg", np.where(tip_force_true[idx_w] > 0.3, 8.0 + 10.0 * np.clip(slack_w / 150.0, 0, 1), np.nan), "%.2f")
    add("gs_sweeps", np.where(t_w > 0, 20 + ccount * 3, 0).astype(float), "%.0f")
    add("tip_path_mm", tip_ms[idx_w], "%.3f")
    add("tip_contact_force_N", tip_force_true[idx_w])
    header.append("tip_region"); cols.append(tip_reg_w)
    write_csv(os.path.join(args.out_dir, "world.csv"), header, cols)

    # -- firmware.csv (every 5 ms) ----------------------------------------------------------
    t_f = np.arange(0.0, T + 1e-9, 0.005)
    idx_f = np.clip(np.round(t_f * 1000.0).astype(int), 0, n_ms - 1)
    n_f = len(t_f)
    lag = max(1, int(round(0.06 / 0.005)))  # the estimate lags ~60 ms
    lagged = np.concatenate([np.full(lag, tip_force_true[0]), tip_force_true[idx_f][:-lag]])
    est_tip_force = np.clip(lagged * 0.93 + rng.normal(0.0, 0.07, n_f), 0.0, None)
    tip_est = tip_ms[idx_f] + 4.0 * np.sin(2 * np.pi * t_f / (11.0 * k)) + rng.normal(0.0, 0.2, n_f)
    ins_f = ins_ms[idx_f]
    win = max(1, int(round(0.5 * k / 0.005)))
    d_ins = ins_f - np.concatenate([np.full(win, ins_f[0]), ins_f[:-win]])
    d_tip = tip_est - np.concatenate([np.full(win, tip_est[0]), tip_est[:-win]])
    moving = np.abs(d_ins) > 3.0
    eff = np.where(moving, d_tip / np.where(moving, d_ins, 1.0), np.nan)
    eff = np.where(moving, np.clip(eff + rng.normal(0.0, 0.02, n_f), -0.5, 1.5), np.nan)
    vel = np.gradient(tip_est, t_f)
    # alarms with hysteresis
    slack_f = slack_ms[idx_f]
    selflock = np.zeros(n_f, int); level = np.zeros(n_f, int)
    on = False; lv = 0
    for i in range(n_f):
        if not on and slack_f[i] > 70.0 and (eff[i] == eff[i]) and eff[i] < 0.3:
            on = True
        elif on and slack_f[i] < 55.0:
            on = False
        selflock[i] = 1 if on else 0
        f = est_tip_force[i]
        if lv == 0 and f > 3.0:
            lv = 1
        if lv <= 1 and f > 4.2:
            lv = 2
        if lv == 2 and f < 3.8:
            lv = 1
        if lv == 1 and f < 2.6:
            lv = 0
        level[i] = lv
    alarms = []
    for kind, series in (("self_lock", selflock), ("contact_force_warning", (level >= 1).astype(int)),
                         ("contact_force_critical", (level >= 2).astype(int))):
        d = np.diff(np.concatenate([[0], series, [0]]))
        for a, b in zip(np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]):
            alarms.append({"kind": kind, "raised_s": round(float(t_f[a]), 3),
                           "cleared_s": None if b >= n_f else round(float(t_f[b]), 3)})
    alarms.sort(key=lambda a: a["raised_s"])

    st_arc = np.arange(N_STATIONS) * STATION_SPACING_MM
    cols, header = [], []
    add("time_s", t_f, "%.3f")
    add("step_index", np.arange(n_f).astype(float), "%.0f")
    add("tip_path_mm", tip_est, "%.2f")
    add("tip_velocity_mm_per_s", vel, "%.2f")
    add("advance_efficiency", eff, "%.3f")
    inserted = ins_f[:, None] >= st_arc[None, :]
    add("active_stations", inserted.sum(axis=1).astype(float), "%.0f")
    st_normal = np.zeros((n_f, N_STATIONS)); st_tang = np.zeros((n_f, N_STATIONS)); st_path = np.full((n_f, N_STATIONS), np.nan)
    compress = np.clip(tip_est / np.maximum(ins_f, 1.0), 0.2, 1.0)
    for s in range(N_STATIONS):
        st_path[:, s] = np.where(inserted[:, s], np.clip(tip_est - st_arc[s] * compress, 0.0, None), np.nan)
    st_normal[:, 0] = est_tip_force * 0.95
    st_tang[:, 0] = est_tip_force * 0.31
    for s in range(1, N_STATIONS):
        in_sig = (st_path[:, s] > colon.sig0 + 30) & (st_path[:, s] < colon.sig1 - 20)
        base = 0.15 + 0.25 * np.abs(np.sin(0.9 * s))
        loop = np.where(in_sig, 0.03 * np.clip(slack_f - 10, 0, None) * (0.6 + 0.4 * np.sin(1.7 * s) ** 2), 0.0)
        st_normal[:, s] = np.where(inserted[:, s], np.clip(base * (s % 3 != 0) + loop + rng.normal(0, 0.03, n_f), 0, None), np.nan)
        st_tang[:, s] = np.where(inserted[:, s], 0.25 * st_normal[:, s] * (0.5 + 0.5 * np.sin(0.4 * s + t_f)), np.nan)
    st_mag = np.hypot(st_normal, st_tang)
    st_state = np.where(np.isnan(st_normal), 0, np.where(st_mag < 0.05, 0, np.where(st_tang < 0.18 * st_normal, 1, 2)))
    mag0 = np.where(np.isnan(st_mag), -1.0, st_mag)
    max_st = np.argmax(mag0, axis=1)
    add("max_contact_force_N", mag0[np.arange(n_f), max_st])
    add("max_contact_station", max_st.astype(float), "%.0f")
    add("max_contact_path_mm", st_path[np.arange(n_f), max_st], "%.2f")
    add("distal_sticking", (st_state[:, 0] == 1).astype(float), "%.0f")
    add("self_lock_alarm", selflock.astype(float), "%.0f")
    add("contact_force_level", level.astype(float), "%.0f")
    add("fault_flags", np.zeros(n_f), "%.0f")
    for s in range(N_STATIONS):
        add(f"station_{s}_arc_mm", np.full(n_f, st_arc[s]), "%.1f")
        add(f"station_{s}_path_mm", st_path[:, s], "%.2f")
        add(f"station_{s}_normal_N", st_normal[:, s], "%.4f")
        add(f"station_{s}_tangential_N", st_tang[:, s], "%.4f")
        add(f"station_{s}_state", st_state[:, s].astype(float), "%.0f")
    write_csv(os.path.join(args.out_dir, "firmware.csv"), header, cols)

    # -- snapshots.json ---------------------------------------------------------------------
    def first(kind, key="raised_s"):
        for a in alarms:
            if a["kind"] == kind and a[key] is not None:
                return a[key]
        return None

    wanted = [(4.0 * k, "advancing through the rectum"), (15.5 * k, "loop forming in the sigmoid")]
    for kind, key, label in (("self_lock", "raised_s", "self-lock alarm raised"),
                             ("contact_force_critical", "raised_s", "contact force critical"),
                             ("self_lock", "cleared_s", "self-lock alarm cleared")):
        v = first(kind, key)
        if v is not None:
            wanted.append((v, label))
    wanted.append((T, "end of run"))
    wanted.sort()
    snaps = []
    for ts, label in wanted:
        i = int(np.clip(round(ts * 1000.0), 0, n_ms - 1))
        c, amp = colon.displaced(tip_ms[i], slack_ms[i])
        nodes = colon.scope_nodes(c, tip_ms[i])
        contacts = []
        # wall pushes the scope inwards: at the loop apex (outer side of the bulge), at the tip,
        # and lightly along the rectum
        def contact(path, fn, outward, tang):
            p = colon.point_at(c, path)
            r = float(np.interp(path, colon.s, colon.radius))
            out = outward / max(np.linalg.norm(outward), 1e-9)
            pos = p + (r - 1.0) * out
            t_dir = colon.tangent_at(c, path)
            f = -fn * out - tang * fn * t_dir
            contacts.append({"position_mm": [round(float(x), 2) for x in pos], "normal_force_N": round(float(fn), 4),
                             "force_N": [round(float(x), 4) for x in f]})

        sl = slack_ms[i]
        if amp > 0:
            a = colon.sig0 + 20.0; b = min(colon.sig1, tip_ms[i] - 25.0)
            for frac, share in ((0.35, 0.6), (0.5, 1.0), (0.65, 0.7)):
                contact(a + frac * (b - a), 0.045 * sl * share + 0.2, colon.bulge_dir, 0.2)
        tp = tip_ms[i]
        tan = colon.tangent_at(c, tp)
        side = np.cross(tan, [0.0, 0.0, 1.0])
        if np.linalg.norm(side) < 1e-6:
            side = np.array([1.0, 0.0, 0.0])
        contact(max(tp - 8.0, 0.0), float(tip_force_true[i]), side, 0.3)
        for pth in (40.0, 100.0):
            if pth < tp - 30:
                contact(pth, 0.4 + 0.002 * pth, np.array([0.3, 0.0, -1.0]), 0.1)
        j = int(np.clip(round(ts / 0.005), 0, n_f - 1))
        est = []
        for s in range(N_STATIONS):
            if not np.isnan(st_path[j, s]):
                est.append({"path_mm": round(float(st_path[j, s]), 2), "normal_N": round(float(st_normal[j, s]), 4),
                            "tangential_N": round(float(st_tang[j, s]), 4)})
        snaps.append({"time_s": round(float(ts), 3), "label": label,
                      "scope_mm": [[round(float(x), 2) for x in p] for p in nodes],
                      "colon_mm": [[round(float(x), 2) for x in p] for p in c],
                      "contacts": contacts, "estimated": est})
    doc = {"colon": {"centerline_mm": [[round(float(x), 3) for x in p] for p in colon.c0],
                     "inner_radius_mm": [round(float(r), 3) for r in colon.radius],
                     "region": colon.region},
           "snapshots": snaps}
    with open(os.path.join(args.out_dir, "snapshots.json"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")

    summary = {"scenario": "synthetic (tests/host_sim/plots/make_sample_run.py)", "kind": "world",
               "description": "synthetic sample run: a sigmoid loop forms and is reduced", "status": "complete",
               "message": "", "failure_time_s": None, "end_time_s": T, "simulated_time_s": T,
               "time_step_s": 0.01, "sample_rate_Hz": 30, "max_handle_force_N": round(float(np.max(np.abs(handle_true))), 4),
               "max_contact_force_N": round(float(np.max(fmax)), 4), "alarms": alarms,
               "files": RUN_FILES}
    with open(os.path.join(args.out_dir, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    print(f"make_sample_run: wrote {args.out_dir}: {n_ms} recording rows, {len(t_w)} world rows, "
          f"{n_f} firmware rows, {len(snaps)} snapshots, {len(alarms)} alarms")
    return 0


if __name__ == "__main__":
    sys.exit(main())
