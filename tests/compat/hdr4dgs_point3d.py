#!/usr/bin/env python3
"""Reads a scene's point3d.ply the way the official HDR-4DGS code does and says how many points
its initialisation keeps (issue 56). Standard library only.

What the official loader does, restated from prinasi/HDR-4DGS (scene/dataset_readers.py,
readNerfSyntheticInfo and fetchPly, commit eff18d2; no code copied):
  - the vertex element's x, y, z; red, green, blue divided by 255; a `time` column if present;
  - when the file holds more points than the config's num_pts (50000 for five HDR-4D-Syn
    scenes, 100000 for three), it draws num_pts indices uniformly WITH replacement
    (np.random.randint), and, when there is a time column, keeps only the drawn points whose time
    is strictly inside time_duration (every config: [0, 1]); at or below num_pts nothing is
    dropped and the times are used as they are;
  - each kept point starts a Gaussian whose time mean is the point's time.
So a cloud whose points sit at t = 0 (datagen before issue 56) keeps none of its points once it
is larger than num_pts, and every Gaussian starts at t = 0 when it is not.

Usage:
  hdr4dgs_point3d.py --ply SCENE/point3d.ply [--num-pts 50000]
      prints what the official loader keeps; exit 0 when it keeps every drawn point.
  hdr4dgs_point3d.py --hdr4d BUILD/cli/hdr4d
      the compatibility test (ctest): datagen writes a paper-sized cloud (100000 points) of the
      ci airplane, which must keep every point at num_pts 50000 and carry times spread inside
      (0, 1); the same cloud at t = 0 must keep none (so the check can fail). Exit 77 (skipped)
      without Blender.
"""
import argparse
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

PAPER_POINTS = 100000  # datagen's paper preset (datagen/scene_presets.cpp)
OFFICIAL_NUM_PTS = (50000, 100000)  # configs/HDR-4D-Syn/*.yaml
TIME_DURATION = (0.0, 1.0)  # every HDR-4DGS config
SKIP = 77

SCALARS = {  # PLY type -> struct code
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
    "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}


class PlyError(Exception):
    pass


def read_header(f, path):
    if f.readline().strip() != b"ply":
        raise PlyError(f"{path}: not a PLY file")
    fmt, elements = None, []
    while True:
        line = f.readline()
        if not line:
            raise PlyError(f"{path}: header without end_header")
        words = line.decode("ascii", "replace").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "end_header":
            return fmt, elements
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if words[1] == "list":
                raise PlyError(f"{path}: list property '{words[-1]}' is not supported")
            if words[1] not in SCALARS:
                raise PlyError(f"{path}: unknown property type '{words[1]}'")
            elements[-1][2].append((words[2], SCALARS[words[1]]))


def read_ply(path):
    """The vertex element as {name: list of values}, as plyfile would give it."""
    with open(path, "rb") as f:
        fmt, elements = read_header(f, path)
        if fmt not in ("binary_little_endian", "ascii"):
            raise PlyError(f"{path}: format {fmt} is not supported here")
        for name, count, props in elements:
            if fmt == "ascii":
                rows = [f.readline().split() for _ in range(count)]
                cols = list(zip(*rows)) if rows else [[] for _ in props]
                values = {p: [float(v) for v in col] for (p, _), col in zip(props, cols)}
            else:
                row = struct.Struct("<" + "".join(code for _, code in props))
                data = f.read(row.size * count)
                if len(data) != row.size * count:
                    raise PlyError(f"{path}: truncated {name} data")
                cols = list(zip(*row.iter_unpack(data))) if count else [[] for _ in props]
                values = {p: list(col) for (p, _), col in zip(props, cols)}
            if name == "vertex":
                for key in ("x", "y", "z", "red", "green", "blue"):
                    if key not in values:
                        raise PlyError(f"{path}: vertex property '{key}' missing")
                return values
    raise PlyError(f"{path}: no vertex element")


def official_initial_times(vertex, num_pts, rng, time_duration=TIME_DURATION):
    """The times of the points the official loader keeps (None for a cloud without time)."""
    count = len(vertex["x"])
    times = vertex.get("time")
    if count <= num_pts:
        return list(times) if times is not None else None
    drawn = [rng.randrange(count) for _ in range(num_pts)]  # with replacement, like randint
    if times is None:
        return None
    low, high = time_duration
    return [times[i] for i in drawn if low < times[i] < high]


def write_ply(path, vertex, time=None):
    """A binary little-endian copy of `vertex` (x y z float, rgb uchar, time float), all points
    at `time` when given: the old datagen's cloud for the negative control."""
    n = len(vertex["x"])
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
              "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
              "property uchar blue\nproperty float time\nend_header\n" % n)
    row = struct.Struct("<fffBBBf")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        for i in range(n):
            t = vertex["time"][i] if time is None else time
            f.write(row.pack(vertex["x"][i], vertex["y"][i], vertex["z"][i], int(vertex["red"][i]),
                             int(vertex["green"][i]), int(vertex["blue"][i]), t))


def report(path, num_pts, seed=0):
    vertex = read_ply(path)
    count = len(vertex["x"])
    kept = official_initial_times(vertex, num_pts, random.Random(seed))
    if kept is None:
        print(f"{path}: {count} points, no time column: every Gaussian's time is drawn at random")
        return True
    drawn = min(count, num_pts)
    distinct = sorted(set(kept))
    print(f"{path}: {count} points; the official loader at num_pts {num_pts} keeps "
          f"{len(kept)} of {drawn} (times: {len(distinct)} distinct, "
          f"{min(distinct) if distinct else '-'} to {max(distinct) if distinct else '-'})")
    return len(kept) == drawn


def run_test(hdr4d):
    blender = os.environ.get("HDR4D_BLENDER") or shutil.which("blender")
    if not blender:
        print("SKIPPED: blender is not installed (bash scripts/install-deps.sh)")
        return SKIP
    failures = []
    with tempfile.TemporaryDirectory(prefix="hdr4d_point3d_") as tmp:
        out = os.path.join(tmp, "data")
        cmd = [hdr4d, "datagen", "--scene", "airplane", "--preset", "ci", "--points",
               str(PAPER_POINTS), "--threads", "2", "--out", out]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            print(f"FAILED: {' '.join(cmd)} exited {run.returncode}\n{run.stderr[-2000:]}")
            return 1
        ply = os.path.join(out, "airplane", "point3d.ply")
        vertex = read_ply(ply)
        times = vertex.get("time")
        if len(vertex["x"]) != PAPER_POINTS or times is None:
            failures.append(f"{ply}: {len(vertex['x'])} points, time column "
                            f"{'present' if times is not None else 'absent'}")
        else:
            if not all(0 < t < 1 for t in times):
                failures.append(f"{ply}: a time outside (0, 1)")
            if len(set(times)) < 2:
                failures.append(f"{ply}: every point at one time {times[0]}")
            for num_pts in OFFICIAL_NUM_PTS:
                if not report(ply, num_pts):
                    failures.append(f"{ply}: points lost at num_pts {num_pts}")
            old = os.path.join(tmp, "point3d_t0.ply")
            write_ply(old, vertex, time=0.0)
            if report(old, OFFICIAL_NUM_PTS[0]):
                failures.append("the t = 0 cloud kept its points: the check cannot fail")
    for f in failures:
        print("FAILED:", f)
    return 1 if failures else 0


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ply", help="a point3d.ply to read as the official loader does")
    parser.add_argument("--num-pts", type=int, default=OFFICIAL_NUM_PTS[0])
    parser.add_argument("--hdr4d", help="run the compatibility test with this hdr4d binary")
    args = parser.parse_args(argv)
    if args.hdr4d:
        return run_test(args.hdr4d)
    if not args.ply or args.num_pts < 1:
        parser.error("give --ply FILE (and --num-pts >= 1) or --hdr4d BINARY")
    try:
        return 0 if report(args.ply, args.num_pts) else 1
    except (OSError, PlyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
