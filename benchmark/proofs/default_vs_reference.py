#!/usr/bin/env python3
"""The default against `--reference`, per scene and seed (issue 55's table).

Reads the TSV files that benchmark/proofs/time_to_quality.sh writes (one row per run: scene,
name, seed, cpu_s, iterations, gaussians, psnr, mu_psnr_aligned, hdr_log_slope, stopped) and
prints a Markdown table: each scene and seed with the reference's run, the candidate's, their
differences, and whether the candidate keeps the issue's rule (held-out LDR within --ldr-tol dB,
aligned mu-PSNR within --hdr-tol dB, and less CPU). A CPU ratio within --same-cpu of 1 reads
"same CPU": on a shared 2-core host the same work moves by 5-15% from run to run. A last table
gives the mean per scene over its seeds.

  python3 default_vs_reference.py WORK/time_to_quality.tsv [...] [--candidate NAME]
      [--ldr-tol 0.2] [--hdr-tol 0.3] [--same-cpu 0.05]
"""
import argparse
import csv
import sys
from collections import defaultdict


def read_rows(paths):
    rows = []
    for path in paths:
        try:
            with open(path, newline="") as f:
                reader = csv.DictReader(f, delimiter="\t")
                need = {"scene", "name", "seed", "cpu_s", "psnr", "mu_psnr_aligned", "gaussians"}
                missing = need - set(reader.fieldnames or [])
                if missing:
                    sys.exit(f"{path}: not a time_to_quality.sh table (no column "
                             f"{', '.join(sorted(missing))})")
                rows.extend(reader)
        except OSError as e:
            sys.exit(f"{path}: cannot read ({e.strerror})")
    return rows


def num(row, key):
    v = row.get(key, "")
    try:
        return float(v) if v != "" else None
    except ValueError:
        sys.exit(f"row {row.get('scene')}/{row.get('name')}/{row.get('seed')}: "
                 f"{key} is not a number: {v!r}")


def diff(a, b, fmt):
    return "–" if a is None or b is None else format(b - a, fmt)


def verdict(ref, cand, ldr_tol, hdr_tol, same_cpu):
    """The issue's rule for one pair: (keeps LDR, keeps HDR or no HDR, speed word)."""
    ldr = cand["psnr"] >= ref["psnr"] - ldr_tol
    hdr = (ref["mu"] is None or cand["mu"] is None or cand["mu"] >= ref["mu"] - hdr_tol)
    ratio = cand["cpu"] / ref["cpu"]
    speed = ("faster" if ratio < 1 - same_cpu else
             "**slower**" if ratio > 1 + same_cpu else "**same CPU**")
    return ldr, hdr, speed


def summary(r):
    parts = [f"{r['cpu']:.1f} s", f"{r['psnr']:.2f} dB"]
    if r["mu"] is not None:
        parts.append(f"{r['mu']:.2f}")
    if r["slope"] is not None:
        parts.append(f"{r['slope']:.3f}")
    parts.append(f"{r['gaussians'] / 1000:.1f}k")
    return ", ".join(parts)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("tsv", nargs="+")
    ap.add_argument("--reference", default="reference")
    ap.add_argument("--candidate", default="default")
    ap.add_argument("--ldr-tol", type=float, default=0.2)
    ap.add_argument("--hdr-tol", type=float, default=0.3)
    ap.add_argument("--same-cpu", type=float, default=0.05,
                    help="a CPU ratio within this of 1 reads as the same CPU")
    a = ap.parse_args()

    runs = defaultdict(dict)  # (scene, seed) -> name -> run
    for row in read_rows(a.tsv):
        runs[(row["scene"], row["seed"])][row["name"]] = {
            "cpu": num(row, "cpu_s"), "psnr": num(row, "psnr"),
            "mu": num(row, "mu_psnr_aligned"), "slope": num(row, "hdr_log_slope"),
            "gaussians": num(row, "gaussians") or 0}

    print(f"| scene | seed | `--{a.reference}` (CPU, LDR, aligned mu, slope, Gaussians) | "
          f"{a.candidate} | CPU ratio | LDR | aligned mu | kept |")
    print("|---|---|---|---|---|---|---|---|")
    by_scene = defaultdict(list)
    incomplete = []
    for (scene, seed) in sorted(runs):
        pair = runs[(scene, seed)]
        ref, cand = pair.get(a.reference), pair.get(a.candidate)
        if ref is None or cand is None:
            incomplete.append(f"{scene} seed {seed}")
            continue
        by_scene[scene].append((ref, cand))
        ldr, hdr, speed = verdict(ref, cand, a.ldr_tol, a.hdr_tol, a.same_cpu)
        kept = ("yes" if ldr and hdr else "**no**") + ", " + speed
        print(f"| {scene} | {seed} | {summary(ref)} | {summary(cand)} | "
              f"{cand['cpu'] / ref['cpu']:.2f} | {diff(ref['psnr'], cand['psnr'], '+.2f')} | "
              f"{diff(ref['mu'], cand['mu'], '+.2f')} | {kept} |")
    print()
    print(f"| scene | seeds | CPU ratio (mean) | LDR (mean) | aligned mu (mean) |")
    print("|---|---|---|---|---|")
    for scene, pairs in sorted(by_scene.items()):
        n = len(pairs)
        ratio = sum(c["cpu"] / r["cpu"] for r, c in pairs) / n
        dl = sum(c["psnr"] - r["psnr"] for r, c in pairs) / n
        mus = [c["mu"] - r["mu"] for r, c in pairs if r["mu"] is not None and c["mu"] is not None]
        dmu = f"{sum(mus) / len(mus):+.2f}" if mus else "–"
        print(f"| {scene} | {n} | {ratio:.2f} | {dl:+.2f} | {dmu} |")
    if incomplete:
        print(f"\nwithout both runs: {', '.join(incomplete)}", file=sys.stderr)


if __name__ == "__main__":
    main()
