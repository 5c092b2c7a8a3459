# Blender script: the point3d.ply datagen wrote before issue 56 (script version 1), for the
# comparison of benchmark/proofs/point3d_over_time.sh: `points` surface points sampled from the
# scene posed at t = 0, every point carrying time 0, with the random stream version 1 used
# (new_rng(seed, "points")) and the colours quantised as core/geometry/ply.cpp writes them.
#   blender -b --factory-startup --python-exit-code 1 -P point3d_at_t0.py -- \
#     --scripts DATAGEN_BLENDER_DIR --scene NAME --seed S --points N --out FILE.ply
import argparse
import struct
import sys


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    for name in ("--scripts", "--scene", "--out"):
        parser.add_argument(name, required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--points", type=int, required=True)
    args = parser.parse_args(argv)
    sys.dont_write_bytecode = True
    sys.path.insert(0, args.scripts)
    import bpy
    import hdr4d_kit as kit
    import hdr4d_scenes

    kit.clear_scene()
    scene_def = hdr4d_scenes.SCENES[args.scene](kit.new_rng(args.seed, args.scene))
    scene_def.update(0.0)
    bpy.context.view_layer.update()
    xyzrgb = kit.sample_surface_points(args.points, kit.new_rng(args.seed, "points"))
    count = len(xyzrgb) // 6
    quantise = lambda c: int(round(min(max(c, 0.0), 1.0) * 255.0))  # noqa: E731
    with open(args.out, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\ncomment written by hdr4d\n"
                 f"element vertex {count}\nproperty float x\nproperty float y\nproperty float z\n"
                 "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                 "property float time\nend_header\n").encode())
        for i in range(0, len(xyzrgb), 6):
            x, y, z, r, g, b = xyzrgb[i:i + 6]
            f.write(struct.pack("<fffBBBf", x, y, z, quantise(r), quantise(g), quantise(b), 0.0))
    print(f"point3d_at_t0: {count} points of {args.scene} at t = 0 -> {args.out}")


main()
