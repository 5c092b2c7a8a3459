#!/usr/bin/env python3
"""Time to quality from held-out curves (issue 55).

Reads runs trained with `hdr4d train --test-every N` (RUN/results.json's `test_curve`: held-out
metrics with the iteration and the training seconds at each evaluation) and answers: when did
each run first reach the reference run's final held-out quality? "Reached" means the held-out
LDR PSNR within --ldr-tolerance dB of the reference's final value and, where both runs have an
HDR log-log slope, that slope within --slope-tolerance of the reference's final one (the
issue's 0.2 dB and 0.02). The reference's own curve is scored the same way, which shows how
early the reference itself was already there.

  python3 time_to_quality_curves.py --reference REF_RUN CANDIDATE_RUN... [--svg OUT.svg]

Prints a Markdown table; --svg draws held-out LDR PSNR against training seconds, one line per
run, and the reference's final value less the tolerance as a dashed line.
"""
import argparse
import json
import math
import os
import sys


def load_curve(run):
    path = os.path.join(run, "results.json")
    try:
        with open(path) as f:
            results = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"{path}: cannot read the run's results ({e})")
    points = []
    for entry in results.get("test_curve", []):
        if "train_seconds" not in entry or entry.get("psnr") is None:
            sys.exit(f"{path}: test_curve entry at iteration {entry.get('iteration')} has no "
                     "train_seconds or psnr (train with --test-every and a build that records "
                     "the training seconds per evaluation)")
        points.append(entry)
    if not points:
        sys.exit(f"{path}: no test_curve (train with --test-every N)")
    points.sort(key=lambda e: e["iteration"])
    # An evaluation on an opacity reset's iteration sees every opacity at 0.01 (about 14 dB on
    # the Syn configuration): the chart leaves those out, the table cannot be misled by them.
    try:
        with open(os.path.join(run, "config.json")) as f:
            opt = json.load(f)["optimization"]
        reset, until = opt["opacity_reset_interval"], opt["densify_until"]
    except (OSError, KeyError, json.JSONDecodeError):
        reset, until = 0, 0
    for e in points:
        e["after_reset"] = bool(reset) and e["iteration"] % reset == 0 and e["iteration"] <= until
    return results, points


def reached(entry, target, ldr_tol, slope_tol):
    if entry["psnr"] < target["psnr"] - ldr_tol:
        return False
    s, t = entry.get("hdr_log_slope"), target.get("hdr_log_slope")
    if s is not None and t is not None and abs(s - t) > slope_tol:
        return False
    return True


def fmt(v, digits=2):
    return "" if v is None else f"{v:.{digits}f}"


def svg_chart(runs, target_psnr, path):
    # The legend sits right of the plot, as wide as its longest label (about 7 px a character).
    right = max(200, 44 + 7 * max(len(label) for label, _, _ in runs))
    w, h, left, bottom, top = 520 + right, 420, 60, 40, 20
    xs = [e["train_seconds"] for _, _, pts in runs for e in pts]
    ys = [e["psnr"] for _, _, pts in runs for e in pts if not e["after_reset"]] + [target_psnr]
    x_max = max(xs) * 1.02
    y_min, y_max = math.floor(min(ys)) - 0.5, math.ceil(max(ys)) + 0.5

    def px(x):
        return left + (w - left - right) * x / x_max

    def py(y):
        return top + (h - top - bottom) * (y_max - y) / (y_max - y_min)

    colours = ["#888888", "#000000", "#1f77b4", "#d62728", "#2ca02c", "#9467bd"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           'font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<line x1="{left}" y1="{h - bottom}" x2="{w - right}" y2="{h - bottom}" stroke="black"/>',
           f'<line x1="{left}" y1="{top}" x2="{left}" y2="{h - bottom}" stroke="black"/>',
           f'<text x="{(left + w - right) / 2}" y="{h - 8}" text-anchor="middle">'
           'training seconds</text>',
           f'<text x="14" y="{(top + h - bottom) / 2}" text-anchor="middle" '
           f'transform="rotate(-90 14 {(top + h - bottom) / 2})">held-out LDR PSNR (dB)</text>']
    step = 10 ** math.floor(math.log10(max(x_max, 1) / 2))
    x = 0
    while x <= x_max:
        out.append(f'<text x="{px(x)}" y="{h - bottom + 15}" text-anchor="middle">{x:g}</text>')
        x += step * (5 if x_max / step > 12 else 1)
    for y in range(int(math.ceil(y_min)), int(y_max) + 1):
        out.append(f'<text x="{left - 6}" y="{py(y) + 4}" text-anchor="end">{y}</text>')
        out.append(f'<line x1="{left}" y1="{py(y)}" x2="{w - right}" y2="{py(y)}" '
                   'stroke="#eeeeee"/>')
    out.append(f'<line x1="{left}" y1="{py(target_psnr)}" x2="{w - right}" y2="{py(target_psnr)}" '
               'stroke="#d62728" stroke-dasharray="5,4"/>')
    for i, (label, _, pts) in enumerate(runs):
        c = colours[i % len(colours)]
        line = " ".join(f"{px(e['train_seconds']):.1f},{py(e['psnr']):.1f}" for e in pts
                        if not e["after_reset"])
        out.append(f'<polyline points="{line}" fill="none" stroke="{c}" stroke-width="2"/>')
        y = top + 16 + 18 * i
        out.append(f'<line x1="{w - right + 8}" y1="{y - 4}" x2="{w - right + 30}" y2="{y - 4}" '
                   f'stroke="{c}" stroke-width="3"/>')
        out.append(f'<text x="{w - right + 36}" y="{y}">{label}</text>')
    y = top + 16 + 18 * len(runs)
    out.append(f'<line x1="{w - right + 8}" y1="{y - 4}" x2="{w - right + 30}" y2="{y - 4}" '
               'stroke="#d62728" stroke-dasharray="5,4"/>')
    out.append(f'<text x="{w - right + 36}" y="{y}">reference final</text>')
    out.append(f'<text x="{w - right + 36}" y="{y + 14}">less the tolerance</text>')
    out.append(f'<text x="{w - right + 8}" y="{y + 40}" font-size="10">evaluations on an opacity</text>')
    out.append(f'<text x="{w - right + 8}" y="{y + 52}" font-size="10">reset\'s iteration left out</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--reference", required=True, help="the reference run folder")
    ap.add_argument("runs", nargs="*", help="candidate run folders")
    ap.add_argument("--ldr-tolerance", type=float, default=0.2)
    ap.add_argument("--slope-tolerance", type=float, default=0.02)
    ap.add_argument("--svg", help="write the curves here")
    a = ap.parse_args()
    ref_results, ref_points = load_curve(a.reference)
    target = ref_points[-1]
    ref_seconds = ref_results["train_seconds"]
    # Labels are the run folders' names: link runs under descriptive names for a figure.
    rows = [(os.path.basename(os.path.normpath(a.reference)) + " (the reference)", a.reference,
             ref_points)] + [(os.path.basename(os.path.normpath(r)), r, load_curve(r)[1])
                             for r in a.runs]
    print(f"reference final: {fmt(target['psnr'])} dB LDR, slope {fmt(target.get('hdr_log_slope'), 3)}, "
          f"aligned mu {fmt(target.get('mu_psnr_aligned'))} dB, {ref_seconds:.0f} s training; "
          f"reached = LDR within {a.ldr_tolerance} dB and slope within {a.slope_tolerance}")
    print("| run | iterations | training s | final LDR | final aligned mu | final slope "
          "| reached at | s to reach | share of the reference's time |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, _, pts in rows:
        last = pts[-1]
        hit = next((e for e in pts if reached(e, target, a.ldr_tolerance, a.slope_tolerance)), None)
        print(f"| {label} | {last['iteration']} | {last['train_seconds']:.0f} | {fmt(last['psnr'])} "
              f"| {fmt(last.get('mu_psnr_aligned'))} | {fmt(last.get('hdr_log_slope'), 3)} "
              f"| {hit['iteration'] if hit else 'not reached'} "
              f"| {fmt(hit['train_seconds'], 0) if hit else ''} "
              f"| {fmt(hit['train_seconds'] / ref_seconds, 2) if hit else ''} |")
    if a.svg:
        svg_chart(rows, target["psnr"] - a.ldr_tolerance, a.svg)


if __name__ == "__main__":
    main()
