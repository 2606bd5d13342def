"""Synthetic recordings with hidden effects, and the rule that judges the discrepancy workflow on
them: shared by the workflow's checks (tests/host_sim/discrepancy/discrepancy_checks.py) and the
robustness sweep (robustness_sweep.py). Debian's python3, standard library only.

A recording is the default colon and scope driven by a scripted procedure, with truth effects
(model/effects/EFFECTS.md) switched on, recorded with `scopekin simulate` (the test bed's sensor
models, host_sim/sensors/SENSORS.md, at their default noise or a multiple of it)."""
import json
import os
import subprocess

# Procedures (insertion from 20 mm in the default colon; the sigmoid starts 158 mm along it).
PROCEDURES = {
    # 25 s to 390 mm: two speeds, a hold, a roll, a short withdrawal.
    "A": [{"action": "advance", "start_s": 0, "end_s": 8, "speed_mm_per_s": 25},
          {"action": "hold", "start_s": 8, "end_s": 9},
          {"action": "advance", "start_s": 9, "end_s": 17, "speed_mm_per_s": 12},
          {"action": "rotate", "start_s": 17, "end_s": 18, "speed_deg_per_s": 30},
          {"action": "withdraw", "start_s": 18, "end_s": 21, "speed_mm_per_s": 15},
          {"action": "advance", "start_s": 21, "end_s": 25, "speed_mm_per_s": 30}],
    # 22 s to 320 mm, the sigmoid only: slow advance, withdrawal, roll the other way.
    "B": [{"action": "advance", "start_s": 0, "end_s": 14, "speed_mm_per_s": 20},
          {"action": "hold", "start_s": 14, "end_s": 15},
          {"action": "withdraw", "start_s": 15, "end_s": 17, "speed_mm_per_s": 20},
          {"action": "rotate", "start_s": 17, "end_s": 18, "speed_deg_per_s": -40},
          {"action": "advance", "start_s": 18, "end_s": 22, "speed_mm_per_s": 15}],
    # 26 s to 570 mm: deeper, into the sigmoid-descending junction where the loop starts.
    "C": [{"action": "advance", "start_s": 0, "end_s": 14, "speed_mm_per_s": 30},
          {"action": "hold", "start_s": 14, "end_s": 15},
          {"action": "withdraw", "start_s": 15, "end_s": 18, "speed_mm_per_s": 25},
          {"action": "advance", "start_s": 18, "end_s": 26, "speed_mm_per_s": 20}],
    # 36 s to 836 mm, a deep insertion: fast, a roll, on through the junction as a sigmoid loop
    # forms (the handle near 50 N), a withdrawal and a slow re-advance into the descending colon.
    "E": [{"action": "advance", "start_s": 0, "end_s": 12, "speed_mm_per_s": 35},
          {"action": "hold", "start_s": 12, "end_s": 13},
          {"action": "rotate", "start_s": 13, "end_s": 14, "speed_deg_per_s": 30},
          {"action": "advance", "start_s": 14, "end_s": 26, "speed_mm_per_s": 30},
          {"action": "withdraw", "start_s": 26, "end_s": 29, "speed_mm_per_s": 30},
          {"action": "advance", "start_s": 29, "end_s": 36, "speed_mm_per_s": 18}],
}


def cycles(speeds, period_s=20.0, advance_s=8.0):
    """Bench cycles: advance, hold 1 s, roll 1 s (alternating), withdraw to the start at 1.5 x the
    speed, hold for the rest of the period."""
    steps, t = [], 0.0
    for k, v in enumerate(speeds):
        back = advance_s / 1.5
        steps += [{"action": "advance", "start_s": t, "end_s": t + advance_s, "speed_mm_per_s": v},
                  {"action": "hold", "start_s": t + advance_s, "end_s": t + advance_s + 1},
                  {"action": "rotate", "start_s": t + advance_s + 1, "end_s": t + advance_s + 2,
                   "speed_deg_per_s": 40 if k % 2 == 0 else -40},
                  {"action": "withdraw", "start_s": t + advance_s + 2, "end_s": t + advance_s + 2 + back,
                   "speed_mm_per_s": 1.5 * v},
                  {"action": "hold", "start_s": t + advance_s + 2 + back, "end_s": t + period_s}]
        t += period_s
    return steps


# 120 s of six cycles to 170-250 mm: longer than the fit budget (80 s), so the fits run on 8 s
# windows restarted from the baseline's states (fit_windows.hpp).
PROCEDURES["D"] = cycles([20, 28, 24, 18, 26, 22])

# The sensors' default noise (host_sim/sensors/SENSORS.md, "Configuration"), to scale it.
DEFAULT_NOISE = {"handle_force_torque": {"force_noise_N": 0.02, "torque_noise_Nmm": 0.5},
                 "em_tracker": {"position_noise_mm": 0.5, "orientation_noise_rad": 0.002},
                 "tip_force": {"force_noise_N": 0.075}}


def noise_times(factor):
    """The sensors' configuration with every noise SD `factor` times its default."""
    return {sensor: {k: v * factor for k, v in keys.items()} for sensor, keys in DEFAULT_NOISE.items()}


# The fitted parameters compared with the truth, per effect (truth key, report key).
COMPARED = {
    "viscoadhesive_friction": [("viscous_coefficient_s_per_mm", "viscous_coefficient_s_per_mm")],
    "mesenteric_retraction": [("stiffness_N_per_mm2", "stiffness_N_per_mm2")],
    "ei_profile": [("tip_factor", "tip_factor"), ("handle_factor", "handle_factor")],
    "ei_scale": [("factor", "factor")],
    "sigmoid_mobility": [("amplitude_N_per_mm", "amplitude_N_per_mm"), ("frequency_Hz", "frequency_Hz")],
    "tissue_stiffening": [("stiffening_per_N", "stiffening_per_N")],
}
TOLERANCE = 0.25       # a fitted parameter within +-25 % of the truth
MIN_REDUCTION = 0.5    # the most affected output's held-out RMS error at least halved


def truth_value(effect, key):
    if effect["name"] == "tissue_stiffening" and key == "stiffening_per_N" and "reference_force_N" in effect:
        return 1.0 / effect["reference_force_N"]
    return effect[key]


def scenario(description, procedure, effects, sensors):
    """The scenario of one recording: the default colon, the CF-Q160L, 10 ms steps."""
    s = {"description": description, "colon": {"bundled": "default"},
         "scope": {"model": "cf_q160l", "length_mm": 1700, "elements": 170},
         "gravity_mm_per_s2": [0, 0, -9810], "initial_insertion_mm": 20, "solver": {"time_step_s": 0.01},
         "procedure": PROCEDURES[procedure]}
    if effects:
        s["truth_effects"] = effects
    if sensors:
        s["sensors"] = sensors
    return s


def record(scopekin, work, description, procedure, seed, effects, sensors):
    """Writes WORK/scenario.json and records it into WORK/recorded; returns the recording's path."""
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, "scenario.json")
    with open(path, "w") as f:
        json.dump(scenario(description, procedure, effects, sensors), f, indent=1)
    p = subprocess.run([scopekin, "simulate", path, "--out", os.path.join(work, "recorded"), "--seed", str(seed),
                        "--quiet"], capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"scopekin simulate {path}: exit {p.returncode}: {p.stderr.strip()[-500:]}")
    return os.path.join(work, "recorded", "recording.csv")


def judge(report, effects):
    """The workflow's result on a recording with `effects` hidden (none: a null recording), by the
    rule of issue 22 and the checks: the right verdict, the right names, every compared parameter
    within 25 % and the most affected output's held-out error at least halved. Returns a dict with
    each criterion, `success` and, when it failed, `why` (the first criterion missed)."""
    named = sorted(e["name"] for e in report.get("effects", []))
    verdict = report.get("verdict")
    # Judged on the part of the recording its encoder decides (report.json "predictability").
    test = report.get("predictability") or {}
    part = {"judged_until_s": test.get("until_s") if test.get("judged_again") else None}
    if not effects:
        ok = verdict == "none"
        return {**part, "verdict": verdict, "named": named, "success": ok,
                "why": None if ok else f"verdict {verdict} ({', '.join(named) or 'no effect'}) on a null recording"}
    hidden = sorted(e["name"] for e in effects)
    result = {**part, "verdict": verdict, "named": named, "verdict_ok": verdict == "named",
              "names_ok": named == hidden}
    # The sets the report gives as explaining the recording as well as the named one: where the
    # hidden set is among them the recording cannot tell it from what was named (still a failure).
    equals = [sorted(s["effects"]) for s in (report.get("equally_consistent") or {}).get("sets", [])]
    result["equally_consistent"] = equals
    result["hidden_listed_as_equal"] = named != hidden and hidden in equals
    fitted = {e["name"]: {p["name"]: p.get("value") for p in e.get("parameters", [])}
              for e in report.get("effects", [])}
    sds = {e["name"]: {p["name"]: p.get("sd") for p in e.get("parameters", [])} for e in report.get("effects", [])}
    errors = []
    for effect in effects:
        for truth_key, report_key in COMPARED[effect["name"]]:
            truth = truth_value(effect, truth_key)
            got = fitted.get(effect["name"], {}).get(report_key)
            rel = None if got is None else (got - truth) / abs(truth)
            errors.append({"effect": effect["name"], "parameter": report_key, "truth": truth, "fitted": got,
                           "sd": sds.get(effect["name"], {}).get(report_key), "relative_error": rel})
    result["parameters"] = errors
    result["parameters_ok"] = all(e["relative_error"] is not None and abs(e["relative_error"]) <= TOLERANCE
                                  for e in errors)
    most = report.get("most_affected_output") or {}
    result["most_affected_output"] = most.get("name")
    result["reduction"] = most.get("reduction")
    result["reduction_ok"] = most.get("reduction") is not None and most["reduction"] >= MIN_REDUCTION
    checks = [("verdict_ok", f"verdict {verdict}"), ("names_ok", f"named {named or 'nothing'}, hidden {hidden}"),
              ("parameters_ok", "parameters " + ", ".join(
                  f"{e['parameter']} {e['fitted']:.4g} vs {e['truth']:.4g}" if e["fitted"] is not None
                  else f"{e['parameter']} not fitted" for e in errors)),
              ("reduction_ok", f"{most.get('name')} held-out error down {100 * (most.get('reduction') or 0):.0f} %")]
    missed = [why for key, why in checks if not result[key]]
    result["success"] = not missed
    result["why"] = missed[0] if missed else None
    return result
