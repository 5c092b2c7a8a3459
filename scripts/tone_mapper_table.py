#!/usr/bin/env python3
"""Summarise several tone_mapper_seeds.sh folders (one per scene) in one Markdown table: per
scene and metric the mean over seeds of each tone mapper, the best in bold, and the mean over
scenes. Usage: tone_mapper_table.py LABEL=DIR [LABEL=DIR ...]"""
import json
import os
import statistics
import sys

MAPPERS = ["dtm", "mlp", "sigmoid", "reinhard", "durand"]
METRICS = [("mu_psnr_gt_max", "mu-law PSNR (GT max)"), ("mu_ssim_gt_max", "mu-law SSIM (GT max)"),
           ("pu21_psnr", "PU21 PSNR"), ("pu21_ssim", "PU21 SSIM"), ("psnr", "LDR PSNR")]


def scene_means(folder):
    runs = {}
    for name in sorted(os.listdir(folder)):
        mapper, _, seed = name.rpartition("-s")
        path = os.path.join(folder, name, "results.json")
        if mapper in MAPPERS and seed.isdigit() and os.path.exists(path):
            with open(path) as f:
                runs.setdefault(mapper, []).append(json.load(f)["test"])
    seeds = {len(v) for v in runs.values()}
    if set(runs) != set(MAPPERS) or len(seeds) != 1:
        sys.exit(f"{folder}: every tone mapper needs the same number of finished seeds")
    return {m: {k: statistics.mean(r[k] for r in runs[m]) for k, _ in METRICS} for m in MAPPERS}, \
        seeds.pop()


def main():
    scenes = [arg.split("=", 1) for arg in sys.argv[1:]]
    if not scenes or any(len(s) != 2 for s in scenes):
        sys.exit(__doc__)
    means = {label: scene_means(folder) for label, folder in scenes}
    for key, title in METRICS:
        print(f"{title}, mean over seeds:\n")
        print("| scene (seeds) | " + " | ".join(MAPPERS) + " |")
        print("|" + "---|" * (len(MAPPERS) + 1))
        rows = [(f"{label} ({means[label][1]})", means[label][0]) for label, _ in scenes]
        rows.append(("mean over scenes", {m: {key: statistics.mean(means[l][0][m][key]
                                                                for l, _ in scenes)}
                                          for m in MAPPERS}))
        for label, by_mapper in rows:
            values = [by_mapper[m][key] for m in MAPPERS]
            fmt = "{:.2f}" if "psnr" in key else "{:.3f}"
            cells = [("**" + fmt.format(v) + "**") if v == max(values) else fmt.format(v)
                     for v in values]
            print(f"| {label} | " + " | ".join(cells) + " |")
        print()


if __name__ == "__main__":
    main()
