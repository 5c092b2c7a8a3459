# Renders one procedural scene to linear float EXR with Cycles on the CPU, following a render
# plan written by `hdr4d datagen` (datagen/blender_render.h). Run headless:
#
#   blender -b --factory-startup --python-exit-code 1 -P render_scene.py -- --plan PLAN.json
#
# Paths in the plan are relative to its folder. Writes, next to the plan: every planned EXR,
# surface points sampled at the plan's point_times (float32 little-endian x y z r g b t per point)
# and render_info.json
# (Blender's version, the camera-to-world matrix of every render, marker positions).
# Prints "HDR4D_RENDERING i n FILE" before and "HDR4D_RENDERED i n FILE" after each render, which
# the driver turns into a progress bar.
import argparse
import json
import math
import os
import sys
from array import array

sys.dont_write_bytecode = True  # keep __pycache__ out of the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import bpy  # noqa: E402

import hdr4d_kit as kit  # noqa: E402
import hdr4d_scenes  # noqa: E402

SCRIPT_VERSION = 3  # 2: points over time (x y z r g b t); 3: mutant's swell reproducible


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_scene.py")
    parser.add_argument("--plan", required=True)
    return parser.parse_args(argv)


def load_plan(path):
    with open(path) as f:
        plan = json.load(f)
    for key in ("scene", "seed", "rig", "cameras", "width", "height", "samples", "threads",
                "camera_angle_x", "points", "point_times", "points_file", "info_file", "renders"):
        if key not in plan:
            raise ValueError(f"{path}: key '{key}' missing")
    if plan["scene"] not in hdr4d_scenes.SCENES:
        raise ValueError(f"{path}: unknown scene '{plan['scene']}'")
    if plan["rig"] not in ("monocular", "multiview"):
        raise ValueError(f"{path}: rig must be monocular or multiview")
    times = plan["point_times"]
    if not times or not all(isinstance(t, (int, float)) and 0 < t < 1 for t in times):
        raise ValueError(f"{path}: point_times must be a non-empty list of times inside (0, 1)")
    if plan.get("layout", "scene") not in ("scene", "capture"):
        raise ValueError(f"{path}: layout must be scene or capture")
    return plan


def configure_render(plan):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = plan["samples"]
    cycles.use_adaptive_sampling = False  # a fixed sample count: same work, same bytes
    cycles.use_denoising = False
    cycles.seed = plan["seed"] % (2 ** 31)
    cycles.use_animated_seed = False
    cycles.max_bounces = 6
    cycles.diffuse_bounces = 3
    cycles.glossy_bounces = 3
    cycles.transmission_bounces = 2
    cycles.volume_bounces = 0
    cycles.transparent_max_bounces = 4
    cycles.caustics_reflective = False
    cycles.caustics_refractive = False
    cycles.sample_clamp_direct = 0.0  # never clip direct light: emitters keep their radiance
    cycles.sample_clamp_indirect = 10.0  # tames fireflies from small bright lights
    cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    cycles.filter_width = 1.5
    render = scene.render
    render.threads_mode = "FIXED" if plan["threads"] > 0 else "AUTO"
    if plan["threads"] > 0:
        render.threads = plan["threads"]
    render.resolution_x = plan["width"]
    render.resolution_y = plan["height"]
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.film_transparent = False
    render.use_motion_blur = False
    render.use_compositing = False
    render.use_sequencer = False
    for name in dir(render):  # no burnt-in or embedded stamps
        if name.startswith("use_stamp"):
            setattr(render, name, False)
    # Standard view transform, no look: the render is the linear scene radiance.
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    image = render.image_settings
    image.file_format = "OPEN_EXR"
    image.color_depth = "32"
    image.exr_codec = "ZIP"
    image.color_mode = "RGB"
    scene.frame_set(1)


def ring_layout(count, held_out=0):
    """(azimuth, elevation) in degrees for `count` fixed cameras: a full ring for large rigs, an
    arc in front (-Y) for small ones; elevations alternate so the views differ in height. The
    last `held_out` of them are novel views: each halfway (in azimuth) between two neighbouring
    ring cameras and lower than both."""
    ring = count - held_out
    if ring >= 8:
        azimuths = [-90 + 360 * k / ring for k in range(ring)]
    else:
        span = 45.0 * (ring - 1)
        azimuths = [-90 - span / 2 + (span * k / (ring - 1) if ring > 1 else 0)
                    for k in range(ring)]
    layout = [(az, 14 if k % 2 == 0 else 32) for k, az in enumerate(azimuths)]
    for j in range(held_out):
        a, b = azimuths[j % ring], azimuths[(j + 1) % ring]
        if b < a:
            b += 360
        layout.append(((a + b) / 2, 6))
    return layout


def capture_layout(count, held_out=0):
    """(azimuth, elevation) in degrees for a calibration rig (datagen --capture): an arc in front
    (-Y) with neighbours 30 degrees apart, so that feature matching links every camera to the
    next, at three heights; the last `held_out` cameras sit halfway between two neighbouring arc
    cameras near the middle, lower than both (novel views). place_rig_camera adds each tripod's
    own distance and aim."""
    ring = count - held_out
    spacing = 30.0
    azimuths = [-90 - spacing * (ring - 1) / 2 + spacing * k for k in range(ring)]
    heights = (12, 26, 19)
    layout = [(az, heights[k % 3]) for k, az in enumerate(azimuths)]
    for j in range(held_out):
        a = azimuths[(ring - 1) // 2 + j % max(1, ring - 1)] if ring > 1 else azimuths[0]
        layout.append((a + spacing / 2, 7))
    return layout


def place_rig_camera(obj, plan, scene_def, camera_id, azimuth, elevation):
    """A capture rig's camera as tripods stand: at its own distance (within 12% of the scene's)
    and aimed at its own point near the target (within 0.35 units across, 0.2 up or down), all
    seeded. Optical axes that all meet in one point at one distance are a critical configuration
    for self-calibration: COLMAP's focal lengths came out 5-7% long on such a rig."""
    rng = kit.new_rng(plan["seed"], f"tripod{camera_id}")
    distance = scene_def.distance * (1 + rng.uniform(-0.12, 0.12))
    aim_at = [scene_def.target[0] + rng.uniform(-0.35, 0.35),
              scene_def.target[1] + rng.uniform(-0.35, 0.35),
              scene_def.target[2] + rng.uniform(-0.2, 0.2)]
    kit.place_camera(obj, scene_def.target, azimuth, elevation, distance)
    kit.aim(obj, aim_at)


def place_extra_view(obj, plan, scene_def, index):
    """A capture's hand-held walk-around view (static/extra/): anywhere along the rig's arc and
    a little beyond, from low to high, nearer or farther than the tripods, aimed loosely at the
    scene; seeded. They give COLMAP more views of the empty scene and are then dropped."""
    rng = kit.new_rng(plan["seed"], f"walk{index}")
    ring = plan["cameras"] - plan.get("held_out_cameras", 0)
    half_span = 30.0 * (ring - 1) / 2 + 15
    azimuth = -90 + rng.uniform(-half_span, half_span)
    elevation = rng.uniform(5, 45)
    distance = scene_def.distance * rng.uniform(0.7, 1.25)
    aim_at = [scene_def.target[0] + rng.uniform(-0.5, 0.5),
              scene_def.target[1] + rng.uniform(-0.5, 0.5),
              scene_def.target[2] + rng.uniform(-0.3, 0.3)]
    kit.place_camera(obj, scene_def.target, azimuth, elevation, distance)
    kit.aim(obj, aim_at)


def monocular_pose(plan, scene_def, time_index, t):
    """One camera moving around the scene: three quarters of an orbit over the sequence, rising
    and falling, with a seeded wobble."""
    rng = kit.new_rng(plan["seed"], f"orbit{time_index}")
    azimuth = -90 + 270 * t + rng.uniform(-6, 6)
    elevation = 24 + 12 * math.sin(2 * math.pi * 1.5 * t) + rng.uniform(-3, 3)
    distance = scene_def.distance * (1 + rng.uniform(-0.04, 0.04))
    return azimuth, elevation, distance


def matrix_rows(matrix):
    return [[float(matrix[r][c]) for c in range(4)] for r in range(4)]


def sample_points_over_time(scene_def, plan):
    """plan["points"] surface points split evenly over plan["point_times"] (the first slices
    take the remainder), each slice from the surfaces at its time and carrying that time: the
    official loader keeps only points whose time is strictly inside its time span."""
    times = plan["point_times"]
    rng = kit.new_rng(plan["seed"], "points")
    out = array("f")
    for k, t in enumerate(times):
        count = plan["points"] // len(times) + (1 if k < plan["points"] % len(times) else 0)
        if count == 0:
            continue
        scene_def.update(t)
        bpy.context.view_layer.update()
        xyzrgb = kit.sample_surface_points(count, rng)
        for i in range(0, len(xyzrgb), 6):
            out.extend(xyzrgb[i:i + 6])
            out.append(t)
    return out


def main():
    args = parse_args()
    plan_path = os.path.abspath(args.plan)
    root = os.path.dirname(plan_path)
    plan = load_plan(plan_path)
    kit.clear_scene()
    configure_render(plan)
    scene_def = hdr4d_scenes.SCENES[plan["scene"]](kit.new_rng(plan["seed"], plan["scene"]))

    cameras = {}
    multiview = plan["rig"] == "multiview"
    held_out = plan.get("held_out_cameras", 0)
    capture = plan.get("layout", "scene") == "capture"
    if capture:
        layout = capture_layout(plan["cameras"], held_out)
    else:
        layout = ring_layout(plan["cameras"], held_out) if multiview else []
    for camera_id in sorted({r["camera_id"] for r in plan["renders"]}):
        obj = kit.camera(f"camera{camera_id:02d}", plan["camera_angle_x"])
        if capture and camera_id >= plan["cameras"]:  # a hand-held view: static only
            place_extra_view(obj, plan, scene_def, camera_id - plan["cameras"])
        elif capture:
            place_rig_camera(obj, plan, scene_def, camera_id, *layout[camera_id])
        elif multiview:
            azimuth, elevation = layout[camera_id]
            kit.place_camera(obj, scene_def.target, azimuth, elevation, scene_def.distance)
        cameras[camera_id] = obj

    # Surface points over the scene's time (the method's initialisation), before any render.
    points = sample_points_over_time(scene_def, plan)
    if sys.byteorder != "little":
        points.byteswap()
    with open(os.path.join(root, plan["points_file"]), "wb") as f:
        points.tofile(f)

    renders = []
    total = len(plan["renders"])
    for i, item in enumerate(plan["renders"], start=1):
        t = float(item["time"])
        print(f"HDR4D_RENDERING {i} {total} {item['file']}", flush=True)
        still = bool(item.get("static", False))  # a capture's static image: the empty scene
        for actor in scene_def.actors:
            actor.hide_render = still
        scene_def.update(t)
        obj = cameras[item["camera_id"]]
        if not multiview:
            azimuth, elevation, distance = monocular_pose(plan, scene_def, item["time_index"], t)
            kit.place_camera(obj, scene_def.target, azimuth, elevation, distance)
        bpy.context.scene.camera = obj
        bpy.context.view_layer.update()
        out = os.path.join(root, item["file"])
        os.makedirs(os.path.dirname(out), exist_ok=True)
        bpy.context.scene.render.filepath = out
        bpy.ops.render.render(write_still=True)
        if not os.path.exists(out):
            raise RuntimeError(f"{out}: Blender rendered frame {i} but wrote no file")
        renders.append({
            "file": item["file"], "camera_id": item["camera_id"],
            "time_index": item["time_index"], "time": t, **({"static": True} if still else {}),
            "transform_matrix": matrix_rows(obj.matrix_world),
            "markers": [[float(x) for x in m] for m in scene_def.markers(t)],
        })
        print(f"HDR4D_RENDERED {i} {total} {item['file']}", flush=True)

    any_camera = next(iter(cameras.values()))
    info = {
        "format": "hdr4d-datagen-render-info",
        "script_version": SCRIPT_VERSION,
        "blender_version": bpy.app.version_string,
        "scene": plan["scene"],
        "camera_angle_x": float(any_camera.data.angle_x),
        "width": plan["width"], "height": plan["height"],
        "points": {"file": plan["points_file"], "count": len(points) // 7,
                   "times": plan["point_times"]},
        "objects": sorted(o.name for o in bpy.context.scene.objects),
        "renders": renders,
    }
    with open(os.path.join(root, plan["info_file"]), "w") as f:
        json.dump(info, f, indent=1)


main()
