#!/usr/bin/env python3
"""A COLMAP text model of undistorted (PINHOLE) images -> a nerfstudio scene at W x H.

Writes OUT/transforms.json (one shared camera, each frame's camera-to-world matrix with
OpenGL axes, as nerfstudio and `hdr4d train` read it), OUT/images/frame_NNNNN.png (the
images in name order, resized by ffmpeg's area filter) and OUT/points.ply (the model's
3D points and colours). Frames whose index is in HELD go to `test_filenames`, so that
`hdr4d train` holds them out and `opensplat_time_to_psnr.py --view` can pick one.

  python3 colmap_to_nerfstudio.py UNDISTORTED OUT W H HELD
    UNDISTORTED: `colmap image_undistorter`'s output folder, with its model converted to
                 text in UNDISTORTED/txt (`colmap model_converter --output_type TXT`)
    HELD: comma-separated frame indices, e.g. 3,8

Made for real captures (benchmark/proofs/capture_scene.sh, issue 55).
"""
import json
import os
import subprocess
import sys


def rows(path):
    try:
        with open(path) as f:
            return [line for line in f if line.strip() and not line.startswith("#")]
    except OSError as e:
        sys.exit(f"{path}: cannot read the COLMAP text model ({e})")


def quat_to_matrix(qw, qx, qy, qz):
    return [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]


def camera_to_world(qw, qx, qy, qz, t):
    """COLMAP stores world-to-camera (R, t) with x right, y down, z forward; nerfstudio wants
    camera-to-world with y up and z backward: the inverse, with its y and z columns negated."""
    r = quat_to_matrix(qw, qx, qy, qz)
    rt = [[r[j][i] for j in range(3)] for i in range(3)]
    centre = [-sum(rt[i][k] * t[k] for k in range(3)) for i in range(3)]
    return [[rt[i][0], -rt[i][1], -rt[i][2], centre[i]] for i in range(3)] + [[0, 0, 0, 1]]


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    src, out, width, height = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    held = {int(x) for x in sys.argv[5].split(",") if x}
    cams = rows(os.path.join(src, "txt", "cameras.txt"))
    if len(cams) != 1 or cams[0].split()[1] != "PINHOLE":
        sys.exit(f"{src}/txt/cameras.txt: expected one PINHOLE camera (run image_undistorter)")
    c = cams[0].split()
    w0, h0 = int(c[2]), int(c[3])
    fx, fy, cx, cy = (float(v) for v in c[4:8])
    sx, sy = width / w0, height / h0
    lines = rows(os.path.join(src, "txt", "images.txt"))
    # images.txt: one line of pose and name, then one line of 2D points (kept even when empty).
    views = sorted((p[9], camera_to_world(*map(float, p[1:5]), [float(v) for v in p[5:8]]))
                   for p in (lines[i].split() for i in range(0, len(lines), 2)))
    if not views:
        sys.exit(f"{src}/txt/images.txt: no registered image")
    os.makedirs(os.path.join(out, "images"), exist_ok=True)
    frames, test = [], []
    for k, (name, matrix) in enumerate(views):
        rel = f"images/frame_{k:05d}.png"
        subprocess.run(["ffmpeg", "-loglevel", "error", "-y", "-i",
                        os.path.join(src, "images", name), "-vf",
                        f"scale={width}:{height}:flags=area", os.path.join(out, rel)], check=True)
        frames.append({"file_path": rel, "transform_matrix": matrix})
        if k in held:
            test.append(rel)
    points = [p.split() for p in rows(os.path.join(src, "txt", "points3D.txt"))]
    with open(os.path.join(out, "points.ply"), "w") as f:
        f.write(f"ply\nformat ascii 1.0\nelement vertex {len(points)}\n"
                "property float x\nproperty float y\nproperty float z\n"
                "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
        for p in points:
            f.write(" ".join(p[1:7]) + "\n")
    doc = {"camera_model": "OPENCV", "fl_x": fx * sx, "fl_y": fy * sy, "cx": cx * sx,
           "cy": cy * sy, "w": width, "h": height, "k1": 0.0, "k2": 0.0, "p1": 0.0, "p2": 0.0,
           "ply_file_path": "points.ply", "frames": frames, "test_filenames": test}
    with open(os.path.join(out, "transforms.json"), "w") as f:
        json.dump(doc, f, indent=1)
    print(f"{out}: {len(frames)} frames at {width}x{height}, {len(points)} points, "
          f"held out {', '.join(test) or 'none'}")


if __name__ == "__main__":
    main()
