# The procedural scenes. Each builder makes its objects and returns a Scene whose update(t) poses
# everything at normalised time t in [0, 1]: rigid motion, non-rigid deformation (armatures,
# shape keys, modifiers) and lights that move, dim or change colour. Radiance spans well over
# 1e4:1: small emitters and sunlit surfaces next to deep shadow under a dim sky.
#
# World axes are Blender's: +Z up, the ground is z = 0, the action stays within about 1.5 units
# of the origin (the method's random initialisation covers [-1.3, 1.3]^3).
import math
from dataclasses import dataclass, field
from typing import Callable

from mathutils import Matrix, Vector

import hdr4d_kit as kit

TWO_PI = 2 * math.pi


@dataclass
class Scene:
    update: Callable[[float], None]
    target: tuple = (0.0, 0.0, 0.6)  # cameras look here
    distance: float = 4.0  # camera distance from the target
    markers: Callable[[float], list] = field(default=lambda t: [])  # world points per time
    # What moves: hidden in a capture's static images (datagen --capture), which show the empty
    # scene as a rig's calibration shots do. Empty: the static images show the scene at t = 0.
    actors: list = field(default_factory=list)


def stage(rng, color_a=(0.55, 0.55, 0.52), color_b=(0.08, 0.08, 0.08), sky=0.005,
          sky_seen=True):
    """A 5 x 5 checkered floor under a dim blue sky (the fill that keeps shadows above zero)."""
    floor = kit.checker("floor", color_a, color_b, scale=3.0)
    kit.mesh_object("floor", kit.grid(5.0, 5.0, 1, 1), floor)
    return kit.set_world((0.45, 0.55, 0.8), sky, seen_by_camera=sky_seen)


def jitter(rng, amount):
    return (rng.random() * 2 - 1) * amount


# ---------------------------------------------------------------------------------------------
# Monocular scenes


def airplane(rng):
    """A plane circles the airfield at sunset: it banks, its wings flex (shape key), its
    propeller spins; a beacon blinks on the tower, the sun sinks and turns orange."""
    stage(rng, (0.35, 0.42, 0.3), (0.06, 0.08, 0.05))
    white = kit.diffuse("paint", (0.8, 0.8, 0.82), roughness=0.35, metallic=0.2)
    dark = kit.diffuse("dark", (0.04, 0.04, 0.05))
    concrete = kit.diffuse("concrete", (0.45, 0.44, 0.42))
    plane = kit.empty("airplane")
    kit.mesh_object("fuselage",
                    kit.transformed(kit.cylinder(0.08, 0.06, 0.95, 16, 4),
                                    Matrix.Rotation(math.pi / 2, 4, "Y")), white, parent=plane)
    kit.mesh_object("nose", kit.uv_sphere(0.08, 16, 8), dark, location=(0.47, 0, 0),
                    parent=plane)
    wings = kit.mesh_object("wings", kit.box((0.2, 1.3, 0.025), (2, 20, 1)), white,
                            location=(0.05, 0, 0.01), parent=plane)
    wings.shape_key_add(name="Basis")
    flex = wings.shape_key_add(name="flex")
    flex.slider_min = -1.0
    for vertex in flex.data:
        vertex.co.z += 0.12 * (vertex.co.y / 0.65) ** 2
    kit.mesh_object("tail", kit.box((0.16, 0.45, 0.02)), white, location=(-0.42, 0, 0.02),
                    parent=plane)
    kit.mesh_object("fin", kit.box((0.15, 0.02, 0.18)), white, location=(-0.42, 0, 0.1),
                    parent=plane)
    prop = kit.mesh_object("propeller", kit.box((0.015, 0.42, 0.035)), dark,
                           location=(0.53, 0, 0), parent=plane)
    red, _, _ = kit.emissive("nav_red", (1.0, 0.05, 0.03), 60.0)
    green, _, _ = kit.emissive("nav_green", (0.05, 1.0, 0.1), 60.0)
    kit.mesh_object("nav_left", kit.uv_sphere(0.025, 8, 6), red, location=(0.05, 0.66, 0.03),
                    parent=plane)
    kit.mesh_object("nav_right", kit.uv_sphere(0.025, 8, 6), green, location=(0.05, -0.66, 0.03),
                    parent=plane)
    # The tower with lit windows and a blinking beacon; a hangar whose shadow the plane crosses.
    kit.mesh_object("tower", kit.box((0.3, 0.3, 1.1), (1, 1, 4)), concrete,
                    location=(-1.1, 0.9, 0.55))
    window, _, _ = kit.emissive("window", (1.0, 0.8, 0.5), 25.0)
    kit.mesh_object("windows", kit.box((0.32, 0.32, 0.08)), window, location=(-1.1, 0.9, 0.95))
    beacon, beacon_strength, _ = kit.emissive("beacon", (1.0, 0.2, 0.1), 500.0)
    kit.mesh_object("beacon", kit.uv_sphere(0.1, 16, 8), beacon, location=(-1.1, 0.9, 1.2))
    beacon_light = kit.point_light("beacon_light", 40.0, (1.0, 0.2, 0.1), 0.1,
                                   (-1.1, 0.9, 1.2))
    kit.mesh_object("hangar", kit.box((1.0, 0.7, 0.55)), concrete, location=(1.0, -0.9, 0.275))
    kit.mesh_object("hangar_roof", kit.box((1.1, 0.8, 0.06)), dark, location=(1.0, -0.9, 0.58))
    sun = kit.sun("sun", 5.0)
    phase = rng.random() * TWO_PI
    blink_period = 0.1 + 0.02 * rng.random()

    def update(t):
        angle = phase + TWO_PI * t
        plane.location = (0.75 * math.cos(angle), 0.75 * math.sin(angle),
                          0.85 + 0.2 * math.sin(2 * angle))
        heading = angle + math.pi / 2
        plane.rotation_euler = (-math.radians(25), 0.15 * math.cos(2 * angle), heading)
        prop.rotation_euler = (TWO_PI * 23.7 * t, 0, 0)
        flex.value = math.sin(TWO_PI * 3 * t)
        blink = 1.0 if (t % blink_period) < blink_period * 0.4 else 0.0
        beacon_strength.default_value = 500.0 * blink
        beacon_light.data.energy = 40.0 * blink
        kit.sun_direction(sun, 200 + 40 * t, 55 - 47 * t)
        sun.data.energy = 5.0 - 3.5 * t
        sun.data.color = kit.warm_color(6500 - 4300 * t)

    return Scene(update, target=(0, 0, 0.5), distance=4.3)


QUADRUPED_BONES = [
    ("body", (-0.32, 0, 0.72), (0.32, 0, 0.72), None),
    ("neck", (0.32, 0, 0.72), (0.45, 0, 1.02), "body"),
    ("head", (0.45, 0, 1.02), (0.66, 0, 0.98), "neck"),
    ("thigh.FL", (0.28, 0.11, 0.7), (0.28, 0.11, 0.38), "body"),
    ("shin.FL", (0.28, 0.11, 0.38), (0.28, 0.11, 0.03), "thigh.FL"),
    ("thigh.FR", (0.28, -0.11, 0.7), (0.28, -0.11, 0.38), "body"),
    ("shin.FR", (0.28, -0.11, 0.38), (0.28, -0.11, 0.03), "thigh.FR"),
    ("thigh.BL", (-0.28, 0.11, 0.7), (-0.28, 0.11, 0.38), "body"),
    ("shin.BL", (-0.28, 0.11, 0.38), (-0.28, 0.11, 0.03), "thigh.BL"),
    ("thigh.BR", (-0.28, -0.11, 0.7), (-0.28, -0.11, 0.38), "body"),
    ("shin.BR", (-0.28, -0.11, 0.38), (-0.28, -0.11, 0.03), "thigh.BR"),
]


def deer(rng):
    """A deer (armature-skinned mesh) walks out from under a barn roof into the sun while its
    legs swing and its head bobs; the lantern under the roof dims and reddens."""
    stage(rng, (0.3, 0.4, 0.15), (0.1, 0.16, 0.05))
    fur = kit.diffuse("fur", (0.45, 0.25, 0.12), roughness=0.8)
    antler = kit.diffuse("antler", (0.75, 0.7, 0.6))
    wood = kit.diffuse("wood", (0.25, 0.14, 0.07))
    bm = kit.transformed(kit.uv_sphere(1.0, 20, 12),
                         Matrix.Translation((0, 0, 0.74)) @ Matrix.Diagonal((0.4, 0.16, 0.17, 1)))
    parts = [bm]
    for name, head, tail, _ in QUADRUPED_BONES:
        if name.startswith(("thigh", "shin")):
            parts.append(kit.capsule(head, tail, 0.045 if name.startswith("thigh") else 0.03,
                                     segments=10, rings=5))
    parts.append(kit.capsule((0.3, 0, 0.72), (0.47, 0, 1.04), 0.07, segments=10, rings=5))
    parts.append(kit.transformed(kit.uv_sphere(1.0, 12, 8),
                                 Matrix.Translation((0.56, 0, 1.0)) @
                                 Matrix.Diagonal((0.12, 0.07, 0.07, 1))))
    body_mesh = kit.merge(parts)
    body = kit.mesh_object("deer_body", body_mesh, fur)
    rig = kit.build_armature("deer_rig", QUADRUPED_BONES)
    kit.skin(body, rig, QUADRUPED_BONES)
    for side in (1, -1):  # antlers follow the head bone rigidly
        for k, (dx, dz) in enumerate(((0.0, 0.22), (0.06, 0.12))):
            horn = kit.mesh_object(f"antler{side}{k}", kit.cylinder(0.012, 0.006, dz, 6),
                                   antler, parent=rig)
            horn.parent_type = "BONE"
            horn.parent_bone = "head"
            horn.location = (side * 0.05, -0.2 + dx, 0.0 + dz / 2)
            horn.rotation_euler = (0, side * 0.4, 0)
    # The barn roof on four posts, the lantern under it.
    kit.mesh_object("roof", kit.box((1.3, 1.6, 0.07)), wood, location=(-1.0, 0.0, 1.55))
    for x in (-1.55, -0.45):
        for y in (-0.7, 0.7):
            kit.mesh_object("post", kit.box((0.07, 0.07, 1.55)), wood, location=(x, y, 0.775))
    lamp, lamp_strength, lamp_color = kit.emissive("lantern", (1.0, 0.7, 0.35), 300.0)
    kit.mesh_object("lantern", kit.uv_sphere(0.1, 16, 8), lamp, location=(-1.0, 0.3, 1.25))
    lantern = kit.point_light("lantern_light", 60.0, (1.0, 0.7, 0.35), 0.1, (-1.0, 0.3, 1.25))
    sun = kit.sun("sun", 6.0)
    kit.sun_direction(sun, 150 + jitter(rng, 10), 62)
    stride = 4 + rng.random()

    def update(t):
        rig.location = (-1.1 + 1.9 * t, 0.05 * math.sin(TWO_PI * t), 0.0)
        phase = TWO_PI * stride * t
        swing = 28 * math.sin(phase)
        for leg, sign in (("FL", 1), ("BR", 1), ("FR", -1), ("BL", -1)):
            # Negative about Y brings a hanging leg forward (+X); the knee folds back as it lifts.
            kit.pose(rig, {f"thigh.{leg}": [("Y", -sign * swing)],
                           f"shin.{leg}": [("Y", 0.8 * max(0.0, sign * swing))]})
        kit.pose(rig, {"neck": [("Y", 10 * math.sin(phase * 0.5))],
                       "head": [("Y", 8 * math.sin(phase))]})
        glow = 1.0 - 0.85 * t
        lamp_strength.default_value = 300.0 * glow
        lantern.data.energy = 60.0 * glow
        color = kit.warm_color(3200 - 1400 * t)
        lamp_color.default_value = (*color, 1.0)
        lantern.data.color = color

    return Scene(update, target=(-0.2, 0, 0.6), distance=4.2)


def lego(rng):
    """A toy excavator: it rolls back and forth, raises its arm and tips its bucket, its flag
    waves (Wave modifier); the work light above cycles colour and its headlights switch on."""
    stage(rng, (0.5, 0.5, 0.5), (0.12, 0.12, 0.12))
    yellow = kit.diffuse("yellow", (0.85, 0.55, 0.03), roughness=0.3)
    black = kit.diffuse("black", (0.02, 0.02, 0.02), roughness=0.5)
    grey = kit.diffuse("grey", (0.3, 0.3, 0.3), roughness=0.4, metallic=0.5)
    red = kit.diffuse("red", (0.7, 0.04, 0.03), roughness=0.5)
    machine = kit.empty("excavator")
    kit.mesh_object("base", kit.box((0.9, 0.55, 0.18)), yellow, location=(0, 0, 0.3),
                    parent=machine)
    for y in (0.33, -0.33):
        kit.mesh_object("track", kit.box((1.0, 0.16, 0.22)), black, location=(0, y, 0.11),
                        parent=machine)
    for i in range(3):
        for j in range(2):
            kit.mesh_object("stud", kit.cylinder(0.045, 0.045, 0.04, 12), yellow,
                            location=(0.12 + 0.13 * i, -0.12 + 0.24 * j, 0.41), parent=machine)
    kit.mesh_object("cab", kit.box((0.36, 0.42, 0.36)), yellow, location=(-0.18, 0, 0.57),
                    parent=machine)
    headlight, headlight_strength, _ = kit.emissive("headlight", (1.0, 0.95, 0.8), 0.0)
    for y in (0.13, -0.13):
        kit.mesh_object("headlight", kit.box((0.02, 0.08, 0.06)), headlight,
                        location=(0.46, y, 0.33), parent=machine)
    beacon, beacon_strength, beacon_color = kit.emissive("cab_beacon", (1.0, 0.45, 0.05), 80.0)
    kit.mesh_object("cab_beacon", kit.uv_sphere(0.07, 16, 8), beacon, location=(-0.18, 0, 0.8),
                    parent=machine)
    beacon_light = kit.point_light("cab_beacon_light", 15.0, (1.0, 0.45, 0.05), 0.07)
    beacon_light.parent = machine
    beacon_light.location = (-0.18, 0, 0.8)
    arm_pivot = kit.empty("arm_pivot", (0.05, 0, 0.55), parent=machine)
    kit.mesh_object("boom", kit.box((0.7, 0.09, 0.09)), grey, location=(0.35, 0, 0),
                    parent=arm_pivot)
    bucket_pivot = kit.empty("bucket_pivot", (0.7, 0, 0), parent=arm_pivot)
    kit.mesh_object("bucket", kit.box((0.18, 0.26, 0.16)), grey, location=(0.06, 0, -0.08),
                    parent=bucket_pivot)
    kit.mesh_object("mast", kit.cylinder(0.012, 0.012, 0.5, 6), grey, location=(-0.3, 0.15, 1.0),
                    parent=machine)
    flag = kit.mesh_object("flag", kit.grid(0.3, 0.18, 16, 8), red, location=(-0.45, 0.15, 1.15),
                           parent=machine)
    flag.rotation_euler = (math.pi / 2, 0, 0)
    wave = flag.modifiers.new("wave", "WAVE")
    wave.use_y = False
    wave.height = 0.025
    wave.width = 0.12
    wave.narrowness = 1.0
    wave.speed = 0.02
    wave.start_position_x = 0.15
    work = kit.area_light("work_light", 250.0, 1.0, location=(0.3, -0.4, 2.4))
    kit.aim(work, (0, 0, 0.3))
    sun = kit.sun("sun", 3.0, kit.warm_color(5000))
    kit.sun_direction(sun, -60 + jitter(rng, 10), 35)
    hue0 = rng.random()

    def update(t):
        machine.location = (0.25 * math.sin(TWO_PI * t), 0, 0)
        arm_pivot.rotation_euler = (0, -math.radians(5 + 30 * math.sin(TWO_PI * 2 * t)), 0)
        bucket_pivot.rotation_euler = (0, math.radians(50 * math.sin(TWO_PI * 2 * t + 1.0)), 0)
        wave.time_offset = -400.0 * t
        headlight_strength.default_value = 0.0 if t < 0.5 else 400.0
        pulse = 0.5 + 0.5 * math.cos(TWO_PI * 6 * t)
        beacon_strength.default_value = 20.0 + 100.0 * pulse
        beacon_light.data.energy = 4.0 + 20.0 * pulse
        hue = (hue0 + t) % 1.0
        work.data.color = hsv(hue, 0.8, 1.0)
        work.data.energy = 250.0 * (0.35 + 0.65 * (0.5 + 0.5 * math.cos(TWO_PI * 3 * t)))

    return Scene(update, target=(0, 0, 0.45), distance=3.6)


def tank(rng):
    """A tank drives out of a wall's shadow into low sun, its turret traverses, its tracks
    ripple (Wave modifier) and its gun fires twice: muzzle flashes over 1e4 times the shade."""
    stage(rng, (0.42, 0.36, 0.26), (0.14, 0.11, 0.07))
    olive = kit.diffuse("olive", (0.2, 0.24, 0.1), roughness=0.7)
    track = kit.diffuse("track", (0.05, 0.05, 0.05), roughness=0.9)
    brick = kit.diffuse("brick", (0.5, 0.2, 0.12), roughness=0.9)
    hull = kit.empty("tank")
    kit.mesh_object("hull", kit.box((0.85, 0.42, 0.16)), olive, location=(0, 0, 0.24),
                    parent=hull)
    waves = []
    for y in (0.26, -0.26):
        tread = kit.mesh_object("tread", kit.box((0.95, 0.12, 0.16), (24, 2, 4)), track,
                                location=(0, y, 0.09), parent=hull)
        modifier = tread.modifiers.new("ripple", "WAVE")
        modifier.use_y = False
        modifier.height = 0.012
        modifier.width = 0.06
        modifier.speed = 0.01
        waves.append(modifier)
    turret = kit.empty("turret", (-0.05, 0, 0.32), parent=hull)
    kit.mesh_object("turret_body", kit.cylinder(0.17, 0.14, 0.12, 16), olive,
                    location=(0, 0, 0.06), parent=turret)
    barrel_pivot = kit.empty("barrel", (0.14, 0, 0.07), parent=turret)
    kit.mesh_object("gun", kit.transformed(kit.cylinder(0.022, 0.02, 0.5, 10),
                                           Matrix.Rotation(math.pi / 2, 4, "Y")), olive,
                    location=(0.25, 0, 0), parent=barrel_pivot)
    flash_mat, flash_strength, _ = kit.emissive("flash", (1.0, 0.75, 0.35), 0.0)
    flash = kit.mesh_object("flash", kit.uv_sphere(0.07, 12, 8), flash_mat,
                            location=(0.56, 0, 0), parent=barrel_pivot)
    flash["hdr4d_no_points"] = True
    flash_light = kit.point_light("flash_light", 0.0, (1.0, 0.75, 0.35), 0.05)
    flash_light.parent = barrel_pivot
    flash_light.location = (0.6, 0, 0)
    kit.mesh_object("wall", kit.box((1.6, 0.15, 0.9), (4, 1, 2)), brick,
                    location=(-0.85, 0.75, 0.45))
    steel = kit.diffuse("steel", (0.4, 0.4, 0.42))
    kit.mesh_object("pole", kit.cylinder(0.025, 0.025, 1.3, 8), steel, location=(1.2, -1.0, 0.65))
    flood, flood_strength, _ = kit.emissive("flood", (0.85, 0.9, 1.0), 120.0)
    kit.mesh_object("floodlight", kit.uv_sphere(0.11, 16, 8), flood, location=(1.2, -1.0, 1.35))
    flood_light = kit.point_light("flood_light", 150.0, (0.85, 0.9, 1.0), 0.11, (1.2, -1.0, 1.35))
    sun = kit.sun("sun", 6.0, kit.warm_color(5200))
    kit.sun_direction(sun, 90 + jitter(rng, 5), 28)
    shots = (0.38 + 0.05 * rng.random(), 0.78 + 0.05 * rng.random())

    def update(t):
        hull.location = (-0.95 + 1.75 * t, -0.1, 0)
        turret.rotation_euler = (0, 0, math.radians(70 * math.sin(TWO_PI * t)))
        recoil = max(kit.smooth_pulse(t, s, 0.08) for s in shots)
        barrel_pivot.location = (0.14 - 0.05 * recoil, 0, 0.07)
        flash_on = max(kit.smooth_pulse(t, s, 0.04) for s in shots)
        flash.hide_render = flash_on <= 0
        flash_strength.default_value = 3000.0 * flash_on
        flash_light.data.energy = 800.0 * flash_on
        for modifier in waves:
            modifier.time_offset = -300.0 * t
        # The floodlight fails and flickers back in the second half.
        flicker = 1.0 if t < 0.55 else 0.5 + 0.5 * math.cos(TWO_PI * 9 * t) ** 2
        flood_strength.default_value = 120.0 * flicker
        flood_light.data.energy = 150.0 * flicker

    return Scene(update, target=(0, 0, 0.35), distance=4.0)


# ---------------------------------------------------------------------------------------------
# Multi-view scenes: a skinned humanoid (hdr4d_kit.humanoid) in four performances.


def hook(rng):
    """A boxer throws hook punches at a swinging bag under a swinging lamp."""
    stage(rng, (0.45, 0.4, 0.35), (0.1, 0.08, 0.06))
    skin_mat = kit.diffuse("skin", (0.6, 0.38, 0.28), roughness=0.5)
    rig, _ = kit.humanoid("boxer", skin_mat)
    leather = kit.diffuse("leather", (0.5, 0.05, 0.04), roughness=0.4)
    bag_pivot = kit.empty("bag_pivot", (-0.72, -0.25, 1.75))
    kit.mesh_object("bag", kit.cylinder(0.14, 0.14, 0.6, 16, 3), leather, location=(0, 0, -0.6),
                    parent=bag_pivot)
    lamp_pivot = kit.empty("lamp_pivot", (0.3, 0.35, 2.3))
    bulb, _, _ = kit.emissive("bulb", (1.0, 0.85, 0.6), 400.0)
    kit.mesh_object("bulb", kit.uv_sphere(0.1, 16, 8), bulb, location=(0, 0, -0.6),
                    parent=lamp_pivot)
    lamp = kit.point_light("lamp", 120.0, (1.0, 0.85, 0.6), 0.07)
    lamp.parent = lamp_pivot
    lamp.location = (0, 0, -0.6)
    sun = kit.sun("window", 4.0, kit.warm_color(5600))
    kit.sun_direction(sun, -30 + jitter(rng, 10), 40)
    punches = 2

    def update(t):
        cycle = (punches * t) % 1.0
        strike = kit.smooth_pulse(cycle, 0.5, 0.6)
        kit.pose(rig, {
            "spine": [("Z", 35 * strike)],
            "upper_arm.R": [("Y", -(40 - 30 * strike)), ("Z", 10 + 60 * strike)],
            "forearm.R": [("Z", 100 - 40 * strike)],
            "upper_arm.L": [("Y", 60), ("Z", -40)],
            "forearm.L": [("Y", -110)],
            "thigh.L": [("Y", -8)], "thigh.R": [("Y", 8), ("X", -15)],
        })
        hit_age = max(0.0, cycle - 0.5)
        bag_pivot.rotation_euler = (0, -0.35 * math.exp(-4 * hit_age) * math.sin(20 * hit_age), 0)
        lamp_pivot.rotation_euler = (0.35 * math.sin(TWO_PI * 1.5 * t), 0, 0)
        sun.data.energy = 4.0 * (1.0 - 0.6 * t)

    return Scene(update, target=(0, 0, 0.8), distance=4.0)


def jump(rng):
    """Jumping jacks under three coloured spot lights whose colours rotate."""
    stage(rng, (0.5, 0.5, 0.55), (0.05, 0.05, 0.06))
    suit = kit.diffuse("suit", (0.2, 0.35, 0.7), roughness=0.5)
    rig, _ = kit.humanoid("jumper", suit)
    spots = []
    for k in range(3):
        angle = TWO_PI * k / 3 + jitter(rng, 0.2)
        spot = kit.spot_light(f"spot{k}", 600.0, cone_deg=35,
                              location=(1.6 * math.cos(angle), 1.6 * math.sin(angle), 2.6))
        kit.aim(spot, (0, 0, 0.7))
        spots.append(spot)
    neon, neon_strength, neon_color = kit.emissive("neon", (1, 1, 1), 40.0)
    kit.mesh_object("neon_ring", kit.band(1.0, 0.07), neon)
    ring_light = kit.point_light("ring_glow", 30.0, (1, 1, 1), 0.5, (0, 0, 0.1))
    sun = kit.sun("sun", 1.5)
    kit.sun_direction(sun, 45, 70)
    jumps = 3

    def update(t):
        phase = (jumps * t) % 1.0
        open_amount = 0.5 - 0.5 * math.cos(TWO_PI * phase)
        rig.location = (0, 0, 0.25 * math.sin(math.pi * phase))
        # Arms from down by the sides (+-75 about Y) to overhead, legs apart.
        kit.pose(rig, {
            "upper_arm.L": [("Y", 75 - 150 * open_amount)],
            "upper_arm.R": [("Y", -75 + 150 * open_amount)],
            "forearm.L": [("Y", -15 * open_amount)], "forearm.R": [("Y", 15 * open_amount)],
            "thigh.L": [("Y", -16 * open_amount)], "thigh.R": [("Y", 16 * open_amount)],
        })
        color = hsv((0.5 + 2 * t) % 1.0, 0.8, 1.0)
        neon_color.default_value = (*color, 1.0)
        ring_light.data.color = color
        neon_strength.default_value = 60.0 * (0.6 + 0.4 * math.sin(TWO_PI * 4 * t))
        for k, spot in enumerate(spots):
            spot.data.color = hsv((t + k / 3) % 1.0, 0.9, 1.0)
            spot.data.energy = 600.0 * (0.4 + 0.6 * (0.5 + 0.5 * math.sin(TWO_PI * (t + k / 3))))

    return Scene(update, target=(0, 0, 0.85), distance=4.0)


def mutant(rng):
    """A hulking creature lumbers out of shadow into a spot light; its muscles swell (shape
    keys) while its eyes glow ever brighter."""
    stage(rng, (0.35, 0.35, 0.38), (0.06, 0.06, 0.07))
    hide = kit.diffuse("hide", (0.25, 0.4, 0.2), roughness=0.6)
    rig, body = kit.humanoid("mutant", hide, bulk=1.45)
    body.shape_key_add(name="Basis")
    swell = body.shape_key_add(name="swell")
    normals = kit.vertex_normals(body.data)  # not vertex.normal: its last bits vary by run
    for vertex, normal, key in zip(body.data.vertices, normals, swell.data):
        p = vertex.co
        bump = 0.5 + 0.5 * math.sin(9 * p.x + 2) * math.sin(7 * p.z + 1) * math.cos(8 * p.y)
        key.co = p + normal * 0.05 * bump
    eye_mat, eye_strength, _ = kit.emissive("eyes", (1.0, 0.3, 0.05), 50.0)
    for x in (0.045, -0.045):
        eye = kit.mesh_object("eye", kit.uv_sphere(0.022, 8, 6), eye_mat, parent=rig)
        eye.parent_type = "BONE"
        eye.parent_bone = "head"
        # Bone-parented objects sit at the bone's tail in its axes: +Y along the bone (up),
        # +Z towards the front for this upright bone.
        eye.location = (x * 1.45, -0.13, 0.14)
    kit.mesh_object("wall", kit.box((0.2, 1.8, 1.8)), kit.diffuse("stone", (0.3, 0.3, 0.3)),
                    location=(-1.3, 0.3, 0.9))
    torch, torch_strength, _ = kit.emissive("torch", (1.0, 0.5, 0.15), 150.0)
    kit.mesh_object("torch", kit.uv_sphere(0.09, 16, 8), torch, location=(-1.15, -0.3, 1.35))
    torch_light = kit.point_light("torch_light", 40.0, (1.0, 0.5, 0.15), 0.09, (-1.1, -0.3, 1.35))
    flicker_phase = rng.random() * TWO_PI
    spot = kit.spot_light("spot", 1500.0, kit.warm_color(4500), cone_deg=40,
                          location=(0.8, -0.6, 2.8))
    kit.aim(spot, (0.5, -0.2, 0.5))
    sun = kit.sun("sun", 3.0)
    kit.sun_direction(sun, 180 + jitter(rng, 8), 30)

    def update(t):
        rig.location = (-0.7 + 1.1 * t, 0.2 - 0.3 * t, 0)
        rig.rotation_euler = (0, 0, math.radians(-10 + 20 * t))
        step = math.sin(TWO_PI * 2 * t)
        kit.pose(rig, {
            "thigh.L": [("X", -25 * step)], "thigh.R": [("X", 25 * step)],
            "shin.L": [("X", 30 * max(0.0, step))], "shin.R": [("X", 30 * max(0.0, -step))],
            "upper_arm.L": [("Y", 55), ("X", 25 * step)],
            "upper_arm.R": [("Y", -55), ("X", -25 * step)],
            "forearm.L": [("X", -40)], "forearm.R": [("X", -40)],
            "spine": [("X", 12 + 8 * abs(step))], "hips": [("Z", 6 * step)],
        })
        swell.value = 0.5 + 0.5 * math.sin(TWO_PI * 1.5 * t)
        eye_strength.default_value = 50.0 + 950.0 * t
        flicker = 0.7 + 0.3 * math.sin(TWO_PI * 7 * t + flicker_phase) * math.sin(TWO_PI * 3 * t)
        torch_strength.default_value = 150.0 * flicker
        torch_light.data.energy = 40.0 * flicker

    return Scene(update, target=(0, 0, 0.8), distance=4.0)


def standup(rng):
    """A figure rises from a stool into a bright overhead beam while a desk lamp warms up."""
    stage(rng, (0.5, 0.45, 0.4), (0.12, 0.1, 0.08))
    cloth = kit.diffuse("cloth", (0.6, 0.6, 0.62), roughness=0.7)
    rig, _ = kit.humanoid("sitter", cloth)
    wood = kit.diffuse("wood", (0.3, 0.17, 0.08))
    kit.mesh_object("stool", kit.box((0.35, 0.35, 0.4)), wood, location=(0, 0.22, 0.2))
    beam = kit.spot_light("beam", 2000.0, (1.0, 0.97, 0.9), cone_deg=22, location=(0, -0.1, 3.0))
    kit.aim(beam, (0, -0.05, 1.2))
    lamp_mat, lamp_strength, _ = kit.emissive("desk_lamp", (1.0, 0.6, 0.3), 0.0)
    kit.mesh_object("desk_lamp", kit.uv_sphere(0.1, 16, 8), lamp_mat, location=(0.8, 0.5, 0.8))
    kit.mesh_object("desk", kit.box((0.5, 0.4, 0.68)), wood, location=(0.8, 0.5, 0.34))
    lamp = kit.point_light("desk_light", 0.0, (1.0, 0.6, 0.3), 0.1, (0.8, 0.5, 0.8))
    sun = kit.sun("sun", 0.8, (0.7, 0.8, 1.0))
    kit.sun_direction(sun, 120 + jitter(rng, 10), 50)

    def update(t):
        rise = 0.5 - 0.5 * math.cos(math.pi * min(1.0, max(0.0, (t - 0.1) / 0.7)))
        sit = 1.0 - rise
        rig.location = (0, 0.1 * sit, -0.3 * sit)
        # Seated: thighs forward (negative about X), shins back down, leaning forward.
        kit.pose(rig, {
            "thigh.L": [("X", -88 * sit)], "thigh.R": [("X", -88 * sit)],
            "shin.L": [("X", 88 * sit)], "shin.R": [("X", 88 * sit)],
            "spine": [("X", 25 * sit)],
            "upper_arm.L": [("Y", 70), ("X", -30 * sit)],
            "upper_arm.R": [("Y", -70), ("X", -30 * sit)],
            "forearm.L": [("X", -50 * sit)], "forearm.R": [("X", -50 * sit)],
        })
        warm = min(1.0, t / 0.6)
        lamp_strength.default_value = 5.0 + 245.0 * warm
        lamp.data.energy = 40.0 * warm

    return Scene(update, target=(0, 0, 0.75), distance=4.0)


# ---------------------------------------------------------------------------------------------
# A novel-view HDR check (not one of the eight): a bulb saturated at every exposure whose power
# changes over time and a spot light that ramps up, seen by a ring of cameras with one held out
# between two of them and lower. Its default response is concave (generator: naka-rushton).


def studio(rng):
    """A ball rolls past a waving figure under a small bare bulb that dims to a fifth while a
    spot light ramps up 20x."""
    # The sky lights the scene but renders black: the held-out camera looks below the ring and
    # would see sky no training view saw.
    stage(rng, (0.55, 0.52, 0.48), (0.07, 0.07, 0.08), sky=0.01, sky_seen=False)
    cloth = kit.diffuse("cloth", (0.25, 0.45, 0.6), roughness=0.6)
    rig, _ = kit.humanoid("figure", cloth, location=(0.35, 0.25, 0))
    rubber = kit.diffuse("rubber", (0.75, 0.2, 0.08), roughness=0.4)
    ball = kit.mesh_object("ball", kit.uv_sphere(0.22, 24, 12), rubber)
    stripe = kit.diffuse("stripe", (0.9, 0.85, 0.2), roughness=0.4)
    kit.mesh_object("stripe", kit.band(0.225, 0.06, 24), stripe, parent=ball)
    bulb, bulb_strength, _ = kit.emissive("bulb", (1.0, 0.8, 0.55), 400.0)
    bulb_position = (-0.55, 0.35, 1.55)
    kit.mesh_object("bulb", kit.uv_sphere(0.07, 16, 8), bulb, location=bulb_position)
    lamp = kit.point_light("bulb_light", 60.0, (1.0, 0.8, 0.55), 0.07, bulb_position)
    spot = kit.spot_light("spot", 40.0, kit.warm_color(6000), cone_deg=30,
                          location=(1.0, -1.1, 2.7))
    kit.aim(spot, (0.2, 0.0, 0.4))
    bulb_power0, spot_power0 = 400.0, 40.0

    def update(t):
        dim = 1.0 - 0.8 * t  # to a fifth
        bulb_strength.default_value = bulb_power0 * dim
        lamp.data.energy = 60.0 * dim
        spot.data.energy = spot_power0 * (1.0 + 19.0 * t)  # 20x
        x = -0.9 + 1.5 * t
        ball.location = (x, -0.45, 0.22)
        ball.rotation_euler = (0, (x + 0.9) / 0.22, 0)
        wave = math.sin(TWO_PI * 1.5 * t)
        kit.pose(rig, {
            "upper_arm.L": [("Y", -60 - 25 * wave)], "forearm.L": [("Y", -30 - 30 * wave)],
            "upper_arm.R": [("Y", -70)], "spine": [("Z", 20 * wave), ("X", 8 * t)],
            "head": [("Z", -15 * wave)],
        })

    return Scene(update, target=(0, 0, 0.6), distance=4.0)


# ---------------------------------------------------------------------------------------------
# A room for rig calibration (datagen --capture, not one of the eight): a floor and three walls
# of non-repeating texture that COLMAP's SIFT can match between fixed cameras, a figure and a
# ball that move through it, a bare bulb that saturates every bracket and a spot light that
# sweeps across the floor.


def room(rng):
    """A figure waves while a ball rolls across a textured room; a spot light sweeps the floor
    under a bare bulb."""
    kit.set_world((0.55, 0.6, 0.7), 0.35)
    floor = kit.speckled("floor", rng, (0.12, 0.1, 0.08), (0.75, 0.62, 0.45), 2.5, 14.0)
    kit.mesh_object("floor", kit.grid(12.0, 12.0, 1, 1), floor)
    wall = kit.speckled("wall", rng, (0.1, 0.14, 0.2), (0.55, 0.7, 0.8), 2.0, 11.0)
    kit.mesh_object("back_wall", kit.box((10.0, 0.1, 3.0)), wall, location=(0, 3.2, 1.5))
    side = kit.speckled("side_wall", rng, (0.2, 0.12, 0.1), (0.8, 0.6, 0.55), 2.0, 11.0)
    for x in (-5.0, 5.0):
        kit.mesh_object("side_wall", kit.box((0.1, 8.0, 3.0)), side, location=(x, -0.8, 1.5))
    crate = kit.speckled("crate", rng, (0.15, 0.2, 0.1), (0.7, 0.75, 0.5), 6.0, 20.0)
    kit.mesh_object("crate", kit.box((0.5, 0.5, 0.5)), crate, location=(-1.1, 0.9, 0.25))
    kit.mesh_object("shelf", kit.box((1.2, 0.35, 0.9)), crate, location=(1.3, 1.4, 0.45))

    cloth = kit.diffuse("cloth", (0.25, 0.45, 0.6), roughness=0.6)
    rig, body = kit.humanoid("figure", cloth, location=(0.3, 0.3, 0))
    rubber = kit.diffuse("rubber", (0.75, 0.2, 0.08), roughness=0.4)
    ball = kit.mesh_object("ball", kit.uv_sphere(0.2, 24, 12), rubber)
    stripe = kit.diffuse("stripe", (0.9, 0.85, 0.2), roughness=0.4)
    ball_stripe = kit.mesh_object("stripe", kit.band(0.205, 0.06, 24), stripe, parent=ball)

    bulb, _, _ = kit.emissive("bulb", (1.0, 0.8, 0.55), 300.0)
    bulb_position = (-0.8, 1.6, 1.9)
    kit.mesh_object("bulb", kit.uv_sphere(0.08, 16, 8), bulb, location=bulb_position)
    kit.point_light("bulb_light", 80.0, (1.0, 0.8, 0.55), 0.08, bulb_position)
    spot = kit.spot_light("spot", 400.0, kit.warm_color(5000), cone_deg=25,
                          location=(0.5, -1.5, 3.0))
    sun = kit.sun("sun", 0.6, (1.0, 0.95, 0.9))
    kit.sun_direction(sun, 60 + jitter(rng, 10), 55)

    def update(t):
        x = -1.0 + 1.8 * t
        ball.location = (x, -0.5, 0.2)
        ball.rotation_euler = (0, (x + 1.0) / 0.2, 0)
        wave = math.sin(TWO_PI * 1.5 * t)
        kit.pose(rig, {
            "upper_arm.L": [("Y", -60 - 25 * wave)], "forearm.L": [("Y", -30 - 30 * wave)],
            "upper_arm.R": [("Y", 70)], "spine": [("Z", 20 * wave)],
            "head": [("Z", -15 * wave)],
        })
        kit.aim(spot, (-0.9 + 1.6 * t, -0.2, 0.0))

    return Scene(update, target=(0, 0.2, 0.7), distance=4.0,
                 actors=[rig, body, ball, ball_stripe])


# ---------------------------------------------------------------------------------------------
# The camera-convention check: a small emissive ball on black, moving so that it visits every
# quadrant of the image. Its centre is reported per render.


MARKER_OFFSETS = [(0.55, 0.25, 0.3), (-0.5, -0.35, -0.3), (0.2, -0.6, 0.45), (-0.3, 0.5, -0.45),
                  (0.0, 0.0, 0.0), (0.6, -0.1, -0.2)]


def marker(rng):
    kit.set_world((0, 0, 0), 0.0)
    material, _, _ = kit.emissive("marker", (1, 1, 1), 20.0)
    ball = kit.mesh_object("marker", kit.uv_sphere(0.05, 24, 12), material)

    def position(t):
        k = min(len(MARKER_OFFSETS) - 1, int(round(t * (len(MARKER_OFFSETS) - 1))))
        return Vector(MARKER_OFFSETS[k]) + Vector((0, 0, 0.6))

    def update(t):
        ball.location = position(t)

    return Scene(update, target=(0, 0, 0.6), distance=4.0,
                 markers=lambda t: [list(position(t))])


def hsv(h, s, v):
    import colorsys
    return colorsys.hsv_to_rgb(h, s, v)


SCENES = {
    "airplane": airplane, "deer": deer, "lego": lego, "tank": tank,
    "hook": hook, "jump": jump, "mutant": mutant, "standup": standup,
    "studio": studio, "room": room, "marker": marker,
}
