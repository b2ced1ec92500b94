#!/usr/bin/env python3
"""plot_bench.py -- the charts of one `iird bench` run (docs/experiments.md reads them).

Reads DIR/frames.csv and DIR/summary.json and writes, into DIR, each as .png and .svg:
  time_vs_error      mean frame time against mean relative MSE, one point per method and setting,
                     log axes, each method's Pareto front as a step line (and the overall front)
  error_over_time    relative MSE at the reference frames, one line per method and setting
  flicker_over_time  flicker at the reference frames' successors
  phases             mean time per phase, stacked bars per method and setting
  vpl_churn          VPLs inserted / deleted / invalidated per frame for iir, regenerations marked

Usage: python3 tools/plot_bench.py DIR [--title TEXT]
Uses matplotlib with the Agg backend; SVGs are deterministic (fixed hash salt, no date).
"""
import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib import ticker  # noqa: E402

plt.rcParams.update({
    "svg.hashsalt": "iir-bench",
    "svg.fonttype": "none",
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "figure.dpi": 100,
})

METHOD_COLOURS = {"iir": "#1f77b4", "ir": "#d62728", "pt": "#2ca02c", "rsm": "#ff7f0e",
                  "ism": "#9467bd", "hier": "#8c564b"}
# Pipeline order; each run has the phases its method declares (summary.json's phase_ms).
PHASES = ["trace", "vpls", "shadowmaps", "maps", "solve", "gather", "gbuffer", "direct", "indirect",
          "filter", "display"]


def colour(method):
    extra = ["#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"]
    return METHOD_COLOURS.get(method, extra[sum(map(ord, method)) % len(extra)])


def shades(runs):
    """A colour per (method, setting): the method's hue, darker for later settings."""
    maps = {"iir": "Blues", "ir": "Reds", "pt": "Greens", "rsm": "Oranges", "ism": "Purples",
            "hier": "copper"}
    out, per_method = {}, {}
    for method, setting in runs:
        per_method.setdefault(method, []).append(setting)
    for method, settings in per_method.items():
        cmap = plt.get_cmap(maps.get(method, "Purples"))
        for k, setting in enumerate(settings):
            t = 0.75 if len(settings) == 1 else 0.4 + 0.55 * k / (len(settings) - 1)
            out[(method, setting)] = cmap(t)
    return out


def number(text):
    """A CSV cell as a float; None when empty or not finite."""
    if text is None or text == "":
        return None
    v = float(text)
    return v if math.isfinite(v) else None


def load(out_dir):
    with open(os.path.join(out_dir, "frames.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(out_dir, "summary.json")) as f:
        summary = json.load(f)
    runs = {}  # (method, setting) -> list of rows, in CSV order
    for r in rows:
        runs.setdefault((r["method"], r["setting"]), []).append(r)
    return runs, summary


def label(method, setting):
    return method if setting == "default" else f"{method} {setting}"


def save(fig, out_dir, name):
    fig.tight_layout()
    for ext in ("png", "svg"):
        meta = {"Date": None} if ext == "svg" else {"Software": None}
        fig.savefig(os.path.join(out_dir, f"{name}.{ext}"), metadata=meta)
    plt.close(fig)


def pareto(points):
    """The points no other point beats in both coordinates (lower is better), sorted by x."""
    front, best = [], math.inf
    for x, y in sorted(points):
        if y < best:
            front.append((x, y))
            best = y
    return front


def step_xy(front, x_end):
    xs = [p[0] for p in front] + [x_end]
    ys = [p[1] for p in front] + [front[-1][1]]
    return xs, ys


def chart_time_vs_error(summary, title, out_dir):
    fig, ax = plt.subplots(figsize=(7, 4.6))
    by_method, everything = {}, []
    for run in summary["runs"]:
        x, y = run.get("mean_ms"), run.get("relmse")
        if x is None or y is None or x <= 0 or y <= 0:
            continue
        by_method.setdefault(run["method"], []).append((x, y, run["setting"]))
        everything.append((x, y))
    if not everything:
        ax.text(0.5, 0.5, "no references: run with --ref-spp > 0", ha="center",
                transform=ax.transAxes)
        save(fig, out_dir, "time_vs_error")
        return
    x_end = max(p[0] for p in everything) * 1.6
    for method, pts in by_method.items():
        c = colour(method)
        ax.scatter([p[0] for p in pts], [p[1] for p in pts], color=c, label=method, zorder=3)
        for x, y, setting in pts:
            if setting != "default":
                ax.annotate(setting, (x, y), textcoords="offset points", xytext=(4, 3),
                            fontsize=7, color=c)
        xs, ys = step_xy(pareto([(p[0], p[1]) for p in pts]), x_end)
        ax.plot(xs, ys, drawstyle="steps-post", color=c, alpha=0.5, lw=1)
    xs, ys = step_xy(pareto(everything), x_end)
    ax.plot(xs, ys, drawstyle="steps-post", color="black", ls="--", lw=1, alpha=0.6,
            label="Pareto front (all)")
    ax.axvline(100, color="grey", ls=":", lw=1)
    ax.annotate("100 ms", (100, 1), xycoords=("data", "axes fraction"), xytext=(3, -12),
                textcoords="offset points", fontsize=7, color="grey")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1, 2, 5)))
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(ticker.NullFormatter())
    ax.set_xlabel("mean frame time (ms), log")
    ax.set_ylabel("mean relative MSE vs pt reference, log")
    ax.set_title(f"time against error -- {title}")
    ax.legend(loc="best", fontsize=8)
    save(fig, out_dir, "time_vs_error")


def chart_over_time(runs, column, ylabel, name, title, out_dir):
    fig, ax = plt.subplots(figsize=(8, 3.8))
    drawn, colours = 0, shades(runs)
    for (method, setting), rows in runs.items():
        pts = [(int(r["frame"]), number(r[column])) for r in rows]
        pts = [(f, v) for f, v in pts if v is not None and v > 0]
        if not pts:
            continue
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", ms=3, lw=1,
                color=colours[(method, setting)], label=label(method, setting))
        drawn += 1
    if drawn:
        ax.set_yscale("log")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=7)
    else:
        ax.text(0.5, 0.5, f"no {column} values (no references)", ha="center",
                transform=ax.transAxes)
    ax.set_xlabel("frame")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{ylabel} over the path -- {title}")
    save(fig, out_dir, name)


def chart_phases(summary, title, out_dir):
    runs = summary["runs"]
    fig, ax = plt.subplots(figsize=(8, 1.1 + 0.32 * len(runs)))
    names = [label(r["method"], r["setting"]) for r in runs]
    left = [0.0] * len(runs)
    cmap = plt.get_cmap("tab10")
    phases = [p for p in PHASES if any(p in r["phase_ms"] for r in runs)]
    phases += sorted({p for r in runs for p in r["phase_ms"]} - set(phases))
    for k, phase in enumerate(phases):
        vals = [(r["phase_ms"].get(phase) or 0.0) for r in runs]
        if not any(vals):
            continue
        ax.barh(names, vals, left=left, color=cmap(k), label=phase)
        left = [a + b for a, b in zip(left, vals)]
    ax.invert_yaxis()
    ax.set_xlabel("mean time per frame (ms)")
    ax.set_title(f"where the frame time goes -- {title}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1), fontsize=7)
    save(fig, out_dir, "phases")


def chart_churn(runs, title, out_dir):
    iir = [(s, rows) for (m, s), rows in runs.items() if m == "iir"]
    n = max(1, len(iir))
    fig, axes = plt.subplots(n, 1, figsize=(7, 1.0 + 1.9 * n), sharex=True, squeeze=False)
    for ax, (setting, rows) in zip(axes[:, 0], iir):
        frames = [int(r["frame"]) for r in rows]
        for col, c in (("vpls_inserted", "#2ca02c"), ("vpls_deleted", "#ff7f0e"),
                       ("vpls_invalidated", "#d62728")):
            ax.plot(frames, [int(r[col]) for r in rows], lw=1, color=c,
                    label=col.replace("vpls_", ""))
        for f, r in zip(frames, rows):
            if int(r["regenerated"]):
                ax.axvline(f, color="black", ls=":", lw=1)
        ax.set_yscale("symlog", linthresh=10)
        ax.set_ylim(bottom=0)
        # k_min, k_max and N read off directly: plain numbers, not powers of ten
        top = max([10] + [int(r[c]) for r in rows for c in ("vpls_inserted", "vpls_deleted",
                                                              "vpls_invalidated")])
        ax.set_yticks([t for t in (0, 2, 4, 6, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096)
                       if t <= top])
        ax.yaxis.set_major_formatter(ticker.ScalarFormatter())
        ax.yaxis.set_minor_locator(ticker.NullLocator())
        ax.set_ylabel("VPLs / frame")
        ax.set_title(f"iir {setting}: VPL churn (dotted: regenerated)", fontsize=9)
        ax.legend(loc="upper right", fontsize=7)
    if not iir:
        axes[0, 0].text(0.5, 0.5, "no iir run", ha="center", transform=axes[0, 0].transAxes)
    axes[-1, 0].set_xlabel("frame")
    fig.suptitle(title, fontsize=9)
    save(fig, out_dir, "vpl_churn")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", help="an iird bench --out folder")
    ap.add_argument("--title", help="chart title (default: scene, path and size)")
    a = ap.parse_args(argv)
    runs, summary = load(a.dir)
    path = os.path.basename(summary.get("path", "")).replace(".json", "")
    title = a.title or f"{summary['scene']}, {path}, {summary['width']}x{summary['height']}"
    chart_time_vs_error(summary, title, a.dir)
    chart_over_time(runs, "relmse", "relative MSE", "error_over_time", title, a.dir)
    chart_over_time(runs, "flicker", "flicker", "flicker_over_time", title, a.dir)
    chart_phases(summary, title, a.dir)
    chart_churn(runs, title, a.dir)
    print(f"charts: {a.dir}/{{time_vs_error,error_over_time,flicker_over_time,phases,vpl_churn}}"
          ".{png,svg}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
