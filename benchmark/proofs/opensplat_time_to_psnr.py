#!/usr/bin/env python3
"""Time to the same held-out PSNR: hdr4d against OpenSplat --cpu on one scene (issue 55).

Both trainers hold out the same view of a nerfstudio scene (hdr4d through `test_filenames` in a
copy of transforms.json, OpenSplat through `--val --val-image NAME`) and both are scored by
`hdr4d eval` on that view's PNG. Steps, one process at a time:

 1. OpenSplat's curve: one run of OS_ITERS steps with `--val-render` (a render of the held-out
    view every 10 steps); every 100th render is scored. The target is OpenSplat's best
    held-out PSNR over the run (it is trained until that stops improving: pass enough steps);
    OpenSplat "got there" at the first scored step within --plateau dB of that best.
 2. OpenSplat's time to that step, without the validation renders: a clean run of exactly that
    many steps with the same --densify-until, whole-process wall seconds, less the wall
    seconds of a 1-step run (loading and start-up, which hdr4d's figure leaves out too).
 3. hdr4d's curve: `hdr4d train --test-every EVERY` (default flags otherwise); its test_curve
    gives the held-out PSNR and the training seconds (evaluations excluded) at each point; the
    first point at or above the target (OpenSplat's best, not less the plateau) is hdr4d's
    time. hdr4d's final render is scored with `hdr4d eval` too, to check that its own
    test metric and `hdr4d eval` agree.

  python3 opensplat_time_to_psnr.py --hdr4d BIN --opensplat BIN --scene SCENE --work DIR
      [--view frame_00005.png] [--opensplat-iters 7000] [--densify-until 3500]
      [--hdr4d-iters 20000] [--test-every 100] [--threads 2] [--hdr4d-args "--max-gaussians N"]

Prints a Markdown summary and writes DIR/summary.json. Meaningful only on an otherwise idle
machine: run nothing beside it.
"""
import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys
import time


def run(cmd, log):
    start = time.monotonic()
    with open(log, "w") as f:
        p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed with {p.returncode}; see {log}")
    return time.monotonic() - start


def held_out_scene(scene, work, view):
    """A copy of SCENE whose transforms.json holds out exactly VIEW (links to the images)."""
    src = os.path.join(scene, "transforms.json")
    try:
        with open(src) as f:
            doc = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        sys.exit(f"{src}: cannot read the scene ({e})")
    paths = [fr["file_path"] for fr in doc.get("frames", [])]
    match = [p for p in paths if os.path.basename(p) == view]
    if len(match) != 1:
        sys.exit(f"{src}: no single frame named {view} (frames: {', '.join(paths[:5])} ...)")
    out = os.path.join(work, "scene")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    for name in os.listdir(scene):
        if name != "transforms.json":
            os.symlink(os.path.abspath(os.path.join(scene, name)), os.path.join(out, name))
    doc["test_filenames"] = match
    with open(os.path.join(out, "transforms.json"), "w") as f:
        json.dump(doc, f, indent=1)
    return out, os.path.join(scene, match[0])


def eval_psnr(hdr4d, pred, truth):
    p = subprocess.run([hdr4d, "eval", "--json", pred, truth], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"hdr4d eval {pred} {truth} failed: {p.stderr.strip()}")
    return json.loads(p.stdout)["mean"]["psnr"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hdr4d", required=True)
    ap.add_argument("--opensplat", required=True)
    ap.add_argument("--scene", required=True, help="a nerfstudio scene (peers' make_scenes.sh)")
    ap.add_argument("--work", required=True)
    ap.add_argument("--view", default="frame_00005.png", help="the held-out image's file name")
    ap.add_argument("--opensplat-iters", type=int, default=7000)
    ap.add_argument("--densify-until", type=int, default=3500,
                    help="OpenSplat's, in both of its runs (its default depends on -n)")
    ap.add_argument("--plateau", type=float, default=0.1)
    ap.add_argument("--hdr4d-iters", type=int, default=20000)
    ap.add_argument("--test-every", type=int, default=100)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--hdr4d-args", default="",
                    help="more `hdr4d train` flags, one string (e.g. \"--max-gaussians 20000\")")
    a = ap.parse_args()
    hdr4d, osplat = os.path.abspath(a.hdr4d), os.path.abspath(a.opensplat)
    os.makedirs(a.work, exist_ok=True)
    scene, truth = held_out_scene(a.scene, a.work, a.view)
    os.environ["OMP_NUM_THREADS"] = str(a.threads)  # libtorch's threads, as hdr4d's --threads

    # 1. OpenSplat's held-out curve.
    val = os.path.join(a.work, "opensplat-val")
    shutil.rmtree(val, ignore_errors=True)
    print(f"OpenSplat: {a.opensplat_iters} steps with a held-out render every 10", flush=True)
    curve_wall = run([osplat, scene, "--cpu", "-n", str(a.opensplat_iters), "--densify-until",
                      str(a.densify_until), "--val", "--val-image", a.view, "--val-render", val,
                      "-o", os.path.join(a.work, "opensplat.ply")],
                     os.path.join(a.work, "opensplat-curve.log"))
    os_curve = []
    for step in range(100, a.opensplat_iters + 1, 100):
        png = os.path.join(val, f"{step}.png")
        if os.path.exists(png):
            os_curve.append((step, eval_psnr(hdr4d, png, truth)))
    if not os_curve:
        sys.exit(f"{val}: OpenSplat wrote no held-out renders")
    best = max(p for _, p in os_curve)
    os_step = next(s for s, p in os_curve if p >= best - a.plateau)

    # 2. OpenSplat's time to that step, without the validation renders.
    print(f"OpenSplat: best {best:.2f} dB; clean run of {os_step} steps", flush=True)
    common = ["--cpu", "--densify-until", str(a.densify_until), "-o",
              os.path.join(a.work, "opensplat-clean.ply")]
    start_wall = run([osplat, scene, "-n", "1"] + common, os.path.join(a.work, "opensplat-1.log"))
    step_wall = run([osplat, scene, "-n", str(os_step)] + common,
                    os.path.join(a.work, "opensplat-clean.log"))
    os_seconds = step_wall - start_wall

    # 3. hdr4d's curve.
    out = os.path.join(a.work, "hdr4d")
    print(f"hdr4d: {a.hdr4d_iters} iterations, held-out view every {a.test_every}", flush=True)
    hdr4d_wall = run([hdr4d, "train", "--data", scene, "--out", out, "--overwrite", "--threads",
                      str(a.threads), "--iterations", str(a.hdr4d_iters), "--test-every",
                      str(a.test_every)] + shlex.split(a.hdr4d_args),
                     os.path.join(a.work, "hdr4d-train.log"))
    with open(os.path.join(out, "results.json")) as f:
        results = json.load(f)
    h_curve = [(e["iteration"], e["psnr"], e["train_seconds"]) for e in results["test_curve"]]
    hit = next(((i, p, s) for i, p, s in h_curve if p >= best), None)
    renders = os.path.join(a.work, "hdr4d-render")
    shutil.rmtree(renders, ignore_errors=True)
    run([hdr4d, "render", "--run", out, "--out", renders, "--threads",
         str(a.threads)], os.path.join(a.work, "hdr4d-render.log"))
    stem = os.path.splitext(a.view)[0]
    pngs = [os.path.join(dp, n) for dp, _, ns in os.walk(renders) for n in ns
            if n.endswith(".png") and os.path.splitext(n)[0] == stem]
    final_eval = eval_psnr(hdr4d, pngs[0], truth) if len(pngs) == 1 else None

    summary = {
        "scene": os.path.abspath(a.scene), "view": a.view,
        "opensplat": {"iters": a.opensplat_iters, "densify_until": a.densify_until,
                      "curve": os_curve, "best_psnr": best, "plateau_db": a.plateau,
                      "step_within_plateau": os_step, "seconds_to_step": os_seconds,
                      "startup_seconds": start_wall, "curve_run_wall": curve_wall},
        "hdr4d": {"iters": a.hdr4d_iters, "args": a.hdr4d_args, "curve": h_curve,
                  "run_wall": hdr4d_wall,
                  "reached": None if hit is None else {"iteration": hit[0], "psnr": hit[1],
                                                       "train_seconds": hit[2]},
                  "final_psnr_results_json": h_curve[-1][1], "final_psnr_eval": final_eval},
    }
    with open(os.path.join(a.work, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(f"| | held-out PSNR | when | training seconds |\n|---|---|---|---|")
    print(f"| OpenSplat best (its plateau) | {best:.2f} dB | first within {a.plateau} dB at step "
          f"{os_step} | {os_seconds:.1f} |")
    if hit:
        print(f"| hdr4d first at or above it | {hit[1]:.2f} dB | iteration {hit[0]} | "
              f"{hit[2]:.1f} ({os_seconds / hit[2]:.1f}x less) |")
    else:
        print(f"| hdr4d | {h_curve[-1][1]:.2f} dB at the end | not reached | |")
    print(f"hdr4d final: {h_curve[-1][1]:.2f} dB in results.json, {final_eval} by hdr4d eval "
          f"of its render")


if __name__ == "__main__":
    main()
