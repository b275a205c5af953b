#!/usr/bin/env python3
"""Writes docs/speed-accuracy.md from the sweeps of scripts/speed_accuracy_report.sh.

For each sweep: its table, its plots, and the runs on the Pareto front of wall time against
the error that matters for the problem: read it as "for an error budget E, the first row with
error <= E is the cheapest setting of the grid that meets it" (measured, not assumed), with its
speed-up over the most expensive run of the grid.
"""
import csv
import datetime
import math
import os
import platform
import sys

SWEEPS = [
    ("butterfly_bolt", "Butterfly bolt (rigid body, Dzhanibekov flip)",
     "orientation_error"),
    ("free_body", "Free asymmetric body (torque-free, 20 s)",
     "orientation_error"),
    ("helix_pull", "Helical rod pulled apart (969 DOF, prescribed motion)",
     "position_error"),
    ("die_throw", "Die throw optimisation (adjoint gradient)",
     "gradient_error"),
    ("tube_insertion", "Rod pushed through a tube (963 DOF, contact and friction)",
     "position_error"),
]
# The integrators at equal accuracy: per sweep, the errors that measure the motion and their
# budgets, 1 % of the scene's scale (a run meets them when every one holds).
BUDGETS = [
    ("butterfly_bolt", [("orientation_error", 1e-2)], "1e-2 rad"),
    ("free_body", [("orientation_error", 1e-2)], "1e-2 rad"),
    ("helix_pull", [("position_error", 2.9e-2)], "2.9e-2 m, 1 % of the 2.86 m pull"),
    ("die_throw", [("position_error", 3e-3), ("orientation_error", 1e-2)],
     "3e-3 m, 1 % of its 0.3 m start height, and 1e-2 rad"),
    ("tube_insertion", [("position_error", 1.6e-2)], "1.6e-2 m, 1 % of the 1.6 m rod"),
]
AXES_END = "frames_requested"  # the first column after the axes


def number(text):
    try:
        return float(text)
    except ValueError:
        return math.nan


def fmt(x, digits=3):
    return "–" if math.isnan(x) else f"{x:.{digits}g}"


def findings(rows, axes, metric):
    """Observations computed from the table: convergence in h."""
    out = []
    if "time_step" in axes:
        # At each setting of the other axes, the error ratio between consecutive time steps.
        others = [a for a in axes if a != "time_step"]
        ratios = []
        groups = {}
        for r in rows:
            if r["failed"] != "1":
                groups.setdefault(tuple(r[a] for a in others), []).append(r)
        for group in groups.values():
            group.sort(key=lambda r: -number(r["time_step"]))
            for a, b in zip(group, group[1:]):
                ea, eb = number(a[metric]), number(b[metric])
                ha, hb = number(a["time_step"]), number(b["time_step"])
                if ea > 0 and eb > 0:
                    ratios.append((ea / eb, ha / hb))
        if ratios:
            rs = sorted(r for r, _ in ratios)
            out.append(f"- Refining h by {fmt(ratios[0][1], 2)}× divides `{metric}` by "
                       f"{fmt(rs[len(rs) // 2], 3)} (median over {len(rs)} pairs of runs, range "
                       f"{fmt(rs[0], 3)} to {fmt(rs[-1], 3)}); first order would be "
                       f"{fmt(ratios[0][1], 2)}.")
    if out:
        out.insert(0, "Findings (computed from the table above):")
        out.insert(1, "")
        out.append("")
    return out


def worst_ratio(run, budgets):
    """The largest error/budget of a run (≤ 1: it meets every budget)."""
    return max(number(run[metric]) / budget for metric, budget in budgets)


INTEGRATORS = ("backward_euler", "trapezoidal", "bdf2")
# Where backward Euler misses the budget on a scene's grid, the script sweeps it alone at
# smaller steps (NAME-backward_euler-fine/): the step where it meets the budget is measured,
# not extrapolated. That sweep has its own, finer reference run.
FINE = "-backward_euler-fine"


def read_sweep(sweep_dir, name):
    """The rows of NAME/sweep.csv, or [] where that sweep was not run."""
    path = os.path.join(sweep_dir, name, "sweep.csv")
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def integrator_section(sweep_dir):
    lines = ["## The integrators at equal accuracy", "",
             "For each scene, the cheapest run of each integrator on its grid whose errors are "
             "within the budgets (1 % of the scene's scale), and backward Euler's wall time over "
             "the cheaper second-order scheme's. Where no run of an integrator meets them, its "
             "most accurate run is shown instead, with how far over the budget it stays.", "",
             "| scene | budget | " + " | ".join(f"{i}: setting, errors, seconds" for i in INTEGRATORS)
             + " | backward Euler / best second-order |", "|---|---|" + "---|" * len(INTEGRATORS) + "---|"]
    fine_notes = []
    for name, budgets, text in BUDGETS:
        rows = read_sweep(sweep_dir, name)
        fine = read_sweep(sweep_dir, name + FINE)
        for r in fine:
            r["fine"] = True
        header = list(rows[0].keys())
        axes = [a for a in header[: header.index(AXES_END)] if a != "integrator"]
        cells, met, shown = [], {}, {}
        for integrator in INTEGRATORS:
            runs = [r for r in rows + fine if r["failed"] != "1" and r["integrator"] == integrator
                    and not math.isnan(worst_ratio(r, budgets))]
            if not runs:
                cells.append("–")
                continue
            meeting = [r for r in runs if worst_ratio(r, budgets) <= 1.0]
            if meeting:
                r = min(meeting, key=lambda r: number(r["wall_seconds"]))
                met[integrator] = r
            else:
                # Ties (a lost orientation reads π at every setting): the costliest of them.
                r = min(runs, key=lambda r: (float(f"{worst_ratio(r, budgets):.3g}"),
                                             -number(r["wall_seconds"])))
            shown[integrator] = number(r["wall_seconds"])
            setting = ", ".join(f"{a}={r[a]}" for a in axes if a in r)
            if "fine" in r:
                setting += f" (the finer sweep `{name}{FINE}`)"
            errors = ", ".join(fmt(number(r[m])) for m, _ in budgets)
            cells.append(f"{setting}: {errors}, {fmt(number(r['wall_seconds']))} s"
                         + ("" if meeting else f" (not met: {fmt(worst_ratio(r, budgets), 2)}× the budget)"))
        second = [i for i in INTEGRATORS[1:] if i in met]
        best = min(second, key=lambda i: number(met[i]["wall_seconds"]), default=None)
        if best is not None and "backward_euler" in met:
            ratio = (f"{fmt(number(met['backward_euler']['wall_seconds']) / number(met[best]['wall_seconds']), 2)}× "
                     f"({best})")
        elif best is not None:
            ratio = (f"backward Euler does not meet it; its most accurate run costs "
                     f"{fmt(shown['backward_euler'] / number(met[best]['wall_seconds']), 2)}× the "
                     f"{best} one")
        elif "backward_euler" in met:
            ratio = "only backward Euler meets it"
        else:
            ratio = "none meets it"
        metrics = " and ".join(f"`{m}`" for m, _ in budgets)
        lines.append(f"| `{name}` | {metrics} ≤ {text} | " + " | ".join(cells) + f" | {ratio} |")
        if fine:
            steps = ", ".join(f"h = {r['time_step']}: " + ", ".join(fmt(number(r[m])) for m, _ in budgets)
                              + f" in {fmt(number(r['wall_seconds']))} s" for r in fine)
            fine_notes.append(f"- `{name}{FINE}`, backward Euler alone at smaller steps "
                              f"(reference: {fine[0]['reference']}): {steps}.")
    lines.append("")
    if fine_notes:
        lines += ["Backward Euler's finer sweeps (errors as in the table's budget column):", ""]
        lines += fine_notes + [""]
    return lines


def machine():
    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} logical CPUs"


def main(sweep_dir, report):
    lines = [
        "# Speed against accuracy",
        "",
        "Generated by `bash scripts/speed_accuracy_report.sh` (do not edit by hand) on "
        f"{datetime.date.today().isoformat()}, {machine()}, Release build. Wall times are the "
        "time steps only, medians of 3 runs; compare them within one table (same machine, same "
        "load), not across machines. Errors are measured by `liedyn sweep` against a reference "
        "run at the grid's smallest time step / 4 and smallest tolerance / 100 (Newton, `lie`, "
        "the trapezoidal rule); see `problems/sweep.hpp` for every definition. The finest runs' errors "
        "therefore read low (by about 1/16 for the trapezoidal rule, 1/4 for backward Euler).",
        "",
        "How to read the tables: `front` marks the runs on the Pareto front (no other run is both "
        "faster and more accurate). The budget tables list the front once more, cheapest first, "
        "counting a run only if it improves the error by at least 1 %: for an error budget E, "
        "the first row with an error ≤ E is the cheapest setting of the grid that meets it. "
        "Iterations count Newton's updates after a step's first solve: a run with fewer "
        "iterations than steps converged at the first solve of some steps, where the step it "
        "solved for is still taken (one assembly and one factorisation; solvers/newton.hpp, "
        "take_final_step).",
        "",
    ]
    lines += integrator_section(sweep_dir)
    for name, title, metric in SWEEPS:
        rows = read_sweep(sweep_dir, name)
        header = list(rows[0].keys())
        axes = header[: header.index(AXES_END)]
        lines += [f"## {title}", "", f"`{name}`: {len(rows)} runs over "
                  + ", ".join(f"`{a}`" for a in axes) + ".", ""]
        cols = axes + ["seconds", "iterations", "unconverged steps", "position error [m]",
                       "orientation error [rad]",
                       "energy drift [J]", "gradient error", "front"]
        lines.append("| " + " | ".join(cols) + " |")
        lines.append("|" + "---|" * len(cols))
        for r in rows:
            cells = [r[a] for a in axes] + [
                fmt(number(r["wall_seconds"])), r["newton_iterations"], r["unconverged_steps"],
                fmt(number(r["position_error"])), fmt(number(r["orientation_error"])),
                fmt(number(r["energy_drift"])), fmt(number(r["gradient_error"])),
                "FAILED" if r["failed"] == "1" else ("*" if r["pareto"] == "1" else "")]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
        ok = [r for r in rows if r["failed"] != "1"]
        slowest = max((number(r["wall_seconds"]) for r in ok), default=math.nan)
        # The front: sorted by time, each run more accurate than every cheaper one.
        front, best = [], math.inf
        for r in sorted(ok, key=lambda r: number(r["wall_seconds"])):
            e = number(r[metric])
            if e < 0.99 * best:  # a gain below 1 % is not worth paying for
                front.append(r)
                best = e
        lines += [f"Error budget → cheapest setting (the Pareto front on `{metric}`; for a "
                  "budget E take the first row with error ≤ E):", "",
                  f"| {metric} | setting | seconds | speed-up over the slowest run |",
                  "|---|---|---|---|"]
        for r in front:
            s = number(r["wall_seconds"])
            setting = ", ".join(f"{a}={r[a]}" for a in axes)
            lines.append(f"| {fmt(number(r[metric]))} | {setting} | {fmt(s)} | "
                         f"{fmt(slowest / s, 2)}× |")
        lines.append("")
        lines += findings(rows, axes, metric)
        for png in sorted(os.listdir(os.path.join(sweep_dir, name))):
            if png.endswith(".png") and png.split("_vs_")[0] in (metric, "position_error",
                                                                  "orientation_error"):
                lines.append(f"![{png}](speed-accuracy/{name}/{png})")
        lines.append("")
    with open(report + ".tmp", "w") as f:
        f.write("\n".join(lines))
    os.replace(report + ".tmp", report)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
