# Building blocks for the procedural scenes: meshes made with bmesh (no operators, so nothing
# depends on a window or an active object), materials, lights, skinned rigs, cameras and the
# surface sampling behind point3d.ply. Everything random draws from a seeded random.Random.
import math
import random
from array import array

import bmesh
import bpy
from mathutils import Matrix, Quaternion, Vector


# ---------------------------------------------------------------------------------------------
# Scene housekeeping


def clear_scene():
    """Removes the factory startup content (cube, camera, light) and every orphan block."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights,
                       bpy.data.cameras, bpy.data.armatures, bpy.data.worlds):
        for block in list(collection):
            collection.remove(block)


def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def set_world(color, strength, seen_by_camera=True):
    """A uniform environment: the dim fill that keeps deep shadows above zero. With
    seen_by_camera False it still lights the scene but renders black behind it (as the method's
    background is), so no view has to explain a sky the others never saw."""
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*color, 1.0)
    background.inputs["Strength"].default_value = strength
    world.cycles_visibility.camera = seen_by_camera
    bpy.context.scene.world = world
    return background.inputs["Strength"]


# ---------------------------------------------------------------------------------------------
# Materials. Each records its mean albedo (or emission colour) in "hdr4d_color": the colour the
# t = 0 point cloud gets.


def _material(name, color):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material["hdr4d_color"] = list(color)
    return material


def diffuse(name, color, roughness=0.6, metallic=0.0):
    material = _material(name, color)
    bsdf = material.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return material


def checker(name, color_a, color_b, scale):
    mean = [(a + b) / 2 for a, b in zip(color_a, color_b)]
    material = _material(name, mean)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.8
    texture = nodes.new("ShaderNodeTexChecker")
    texture.inputs["Color1"].default_value = (*color_a, 1.0)
    texture.inputs["Color2"].default_value = (*color_b, 1.0)
    texture.inputs["Scale"].default_value = scale
    coords = nodes.new("ShaderNodeTexCoord")
    links.new(coords.outputs["Object"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    return material


def speckled(name, rng, color_a, color_b, scale, detail_scale):
    """A non-repeating pattern that feature matchers (COLMAP's SIFT) lock on to: cells of random
    colour (Voronoi) between `color_a` and `color_b`, each broken up by fine high-contrast noise.
    `scale` sets the cell count per unit, `detail_scale` the noise's; a seeded offset moves the
    pattern so seeds differ."""
    mean = [(a + b) / 2 for a, b in zip(color_a, color_b)]
    material = _material(name, mean)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.85
    bsdf.inputs["Specular"].default_value = 0.2
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Location"].default_value = tuple(rng.uniform(-50, 50) for _ in range(3))
    links.new(coords.outputs["Object"], mapping.inputs["Vector"])
    cells = nodes.new("ShaderNodeTexVoronoi")
    cells.inputs["Scale"].default_value = scale
    links.new(mapping.outputs["Vector"], cells.inputs["Vector"])
    cell_ramp = nodes.new("ShaderNodeValToRGB")  # cell colour (a random grey) -> a to b
    cell_ramp.color_ramp.elements[0].color = (*color_a, 1.0)
    cell_ramp.color_ramp.elements[1].color = (*color_b, 1.0)
    to_bw = nodes.new("ShaderNodeRGBToBW")
    links.new(cells.outputs["Color"], to_bw.inputs["Color"])
    links.new(to_bw.outputs["Val"], cell_ramp.inputs["Fac"])
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = detail_scale
    noise.inputs["Detail"].default_value = 6.0
    links.new(mapping.outputs["Vector"], noise.inputs["Vector"])
    noise_ramp = nodes.new("ShaderNodeValToRGB")  # contrast: dark blots on a light ground
    noise_ramp.color_ramp.elements[0].position = 0.42
    noise_ramp.color_ramp.elements[0].color = (0.25, 0.25, 0.25, 1.0)
    noise_ramp.color_ramp.elements[1].position = 0.58
    noise_ramp.color_ramp.elements[1].color = (1.0, 1.0, 1.0, 1.0)
    links.new(noise.outputs["Fac"], noise_ramp.inputs["Fac"])
    multiply = nodes.new("ShaderNodeMixRGB")
    multiply.blend_type = "MULTIPLY"
    multiply.inputs["Fac"].default_value = 1.0
    links.new(cell_ramp.outputs["Color"], multiply.inputs["Color1"])
    links.new(noise_ramp.outputs["Color"], multiply.inputs["Color2"])
    links.new(multiply.outputs["Color"], bsdf.inputs["Base Color"])
    return material


def emissive(name, color, strength):
    """Returns (material, strength socket, colour socket): both can be animated."""
    material = _material(name, color)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.remove(nodes["Principled BSDF"])
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*color, 1.0)
    emission.inputs["Strength"].default_value = strength
    links.new(emission.outputs["Emission"], nodes["Material Output"].inputs["Surface"])
    # Blender 3.4's Cycles renders scenes whose emissive meshes are light-sampled (multiple
    # importance sampling) differently from run to run, even on one thread; without it the same
    # seed gives the same bytes. Emitters stay exact where seen; the lamps that light the scene
    # are real lights placed with them.
    material.cycles.sample_as_light = False
    material["hdr4d_emitter"] = True
    return material, emission.inputs["Strength"], emission.inputs["Color"]


# ---------------------------------------------------------------------------------------------
# Meshes


def mesh_object(name, bm, material=None, location=(0, 0, 0), parent=None):
    """Flat shaded on purpose: Blender 3.4's Cycles interpolates smooth vertex normals with
    run-to-run differences in the last bits, which would break same seed, same bytes."""
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    if material is not None:
        mesh.materials.append(material)
        if material.get("hdr4d_emitter"):
            # Seen by the camera only: with light sampling off (see emissive), diffuse rays that
            # happen to hit a small bright emitter would speckle the scene with fireflies. The
            # light it casts comes from a real lamp placed with it.
            obj.visible_diffuse = obj.visible_glossy = obj.visible_transmission = False
            obj.visible_volume_scatter = obj.visible_shadow = False
    obj.location = location
    if parent is not None:
        obj.parent = parent
    return link(obj)


def box(size, segments=(1, 1, 1)):
    """An axis-aligned box centred at the origin with size (x, y, z); `segments` subdivides each
    axis so that deforming modifiers have vertices to move."""
    bm = bmesh.new()
    half = [s / 2 for s in size]
    for axis in range(3):
        u_axis, v_axis = [a for a in range(3) if a != axis]
        nu, nv = segments[u_axis], segments[v_axis]
        for sign in (-1, 1):
            corners = {}
            for i in range(nu + 1):
                for j in range(nv + 1):
                    p = [0.0, 0.0, 0.0]
                    p[axis] = sign * half[axis]
                    p[u_axis] = -half[u_axis] + size[u_axis] * i / nu
                    p[v_axis] = -half[v_axis] + size[v_axis] * j / nv
                    corners[i, j] = bm.verts.new(p)
            for i in range(nu):
                for j in range(nv):
                    bm.faces.new([corners[i, j], corners[i + 1, j], corners[i + 1, j + 1],
                                  corners[i, j + 1]])
    # The six grids share their edge vertices: merge them, then orient every face outwards.
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-6)
    bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
    return bm


def uv_sphere(radius, segments=24, rings=12):
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius)
    return bm


def cylinder(radius_bottom, radius_top, depth, segments=16, rings=1):
    """Along +Z, centred at the origin; `rings` subdivides the height for bending."""
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments,
                          radius1=radius_bottom, radius2=radius_top, depth=depth)
    if rings > 1:
        side_edges = [e for e in bm.edges
                      if abs(e.verts[0].co.z - e.verts[1].co.z) > depth * 0.5]
        bmesh.ops.subdivide_edges(bm, edges=side_edges, cuts=rings - 1, use_grid_fill=True)
    return bm


def band(radius, height, segments=48):
    """An open cylinder wall (a neon ring) standing on z = 0."""
    bm = bmesh.new()
    bottom, top = [], []
    for i in range(segments):
        a = 2 * math.pi * i / segments
        bottom.append(bm.verts.new((radius * math.cos(a), radius * math.sin(a), 0.0)))
        top.append(bm.verts.new((radius * math.cos(a), radius * math.sin(a), height)))
    for i in range(segments):
        j = (i + 1) % segments
        bm.faces.new([bottom[i], bottom[j], top[j], top[i]])
    return bm


def grid(size_x, size_y, cuts_x, cuts_y):
    bm = bmesh.new()
    bmesh.ops.create_grid(bm, x_segments=cuts_x, y_segments=cuts_y, size=0.5)
    bmesh.ops.scale(bm, vec=(size_x, size_y, 1.0), verts=bm.verts)
    return bm


def transformed(bm, matrix):
    bmesh.ops.transform(bm, matrix=matrix, verts=bm.verts)
    return bm


def merge(parts):
    """One bmesh holding every part (each is consumed)."""
    bm = bmesh.new()
    for part in parts:
        mesh = bpy.data.meshes.new("hdr4d_tmp")
        part.to_mesh(mesh)
        part.free()
        bm.from_mesh(mesh)
        bpy.data.meshes.remove(mesh)
    return bm


def empty(name, location=(0, 0, 0), parent=None):
    obj = bpy.data.objects.new(name, None)
    obj.location = location
    if parent is not None:
        obj.parent = parent
    return link(obj)


# ---------------------------------------------------------------------------------------------
# Lights


def sun(name, strength, color=(1, 1, 1), angle_deg=2.0):
    light = bpy.data.lights.new(name, "SUN")
    light.energy = strength
    light.color = color
    light.angle = math.radians(angle_deg)
    return link(bpy.data.objects.new(name, light))


def point_light(name, power, color=(1, 1, 1), radius=0.05, location=(0, 0, 0)):
    light = bpy.data.lights.new(name, "POINT")
    light.energy = power
    light.color = color
    light.shadow_soft_size = radius
    obj = link(bpy.data.objects.new(name, light))
    obj.location = location
    return obj


def spot_light(name, power, color=(1, 1, 1), cone_deg=40.0, location=(0, 0, 0)):
    light = bpy.data.lights.new(name, "SPOT")
    light.energy = power
    light.color = color
    light.spot_size = math.radians(cone_deg)
    light.spot_blend = 0.15
    light.shadow_soft_size = 0.05
    obj = link(bpy.data.objects.new(name, light))
    obj.location = location
    return obj


def area_light(name, power, size, color=(1, 1, 1), location=(0, 0, 0)):
    light = bpy.data.lights.new(name, "AREA")
    light.energy = power
    light.size = size
    light.color = color
    obj = link(bpy.data.objects.new(name, light))
    obj.location = location
    return obj


def aim(obj, target):
    """Points an object's -Z axis (lights and cameras look down -Z) at `target`, +Y up."""
    direction = Vector(target) - obj.location
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = direction.to_track_quat("-Z", "Y")


def sun_direction(obj, azimuth_deg, elevation_deg):
    """Orients a sun so that its light arrives from (azimuth, elevation)."""
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    towards_sun = Vector((math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)))
    obj.rotation_mode = "QUATERNION"
    obj.rotation_quaternion = (-towards_sun).to_track_quat("-Z", "Y")


def warm_color(kelvin):
    """An approximate blackbody colour (linear RGB, max 1) for 1000..12000 K: sunsets and lamps
    that change colour as they dim."""
    t = max(1000.0, min(12000.0, kelvin)) / 100.0
    r = 1.0 if t <= 66 else min(1.0, 1.2929 * (t - 60) ** -0.1332)
    g = (0.3901 * math.log(t) - 0.6318) if t <= 66 else 1.1298 * (t - 60) ** -0.0755
    b = 1.0 if t >= 66 else (0.0 if t <= 19 else 0.5432 * math.log(t - 10) - 1.1962)
    srgb = [min(1.0, max(0.0, c)) for c in (r, g, b)]
    return tuple(c ** 2.2 for c in srgb)


# ---------------------------------------------------------------------------------------------
# Skinned rigs: one mesh deformed by an armature, weights from the distance to each bone.


def build_armature(name, bones, location=(0, 0, 0)):
    """bones: list of (name, head, tail, parent or None). Returns the armature object."""
    data = bpy.data.armatures.new(name)
    obj = link(bpy.data.objects.new(name, data))
    obj.location = location
    view_layer = bpy.context.view_layer
    view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    for bone_name, head, tail, parent in bones:
        bone = data.edit_bones.new(bone_name)
        bone.head, bone.tail = Vector(head), Vector(tail)
        if parent is not None:
            bone.parent = data.edit_bones[parent]
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


def _segment_distance(p, a, b):
    ab = b - a
    denom = ab.dot(ab)
    s = 0.0 if denom <= 1e-12 else max(0.0, min(1.0, (p - a).dot(ab) / denom))
    return (p - (a + ab * s)).length


def skin(mesh_obj, armature_obj, bones, falloff=0.04):
    """Weights every vertex to the bones within `falloff` of its nearest bone, inversely to the
    distance, so joints bend smoothly; then deforms the mesh with an Armature modifier."""
    segments = [(name, Vector(h), Vector(t)) for name, h, t, _ in bones]
    groups = {name: mesh_obj.vertex_groups.new(name=name) for name, _, _ in segments}
    for vertex in mesh_obj.data.vertices:
        p = vertex.co
        distances = [(_segment_distance(p, h, t), name) for name, h, t in segments]
        nearest = min(d for d, _ in distances)
        chosen = [(d, name) for d, name in distances if d <= nearest + falloff]
        weights = [(1.0 / (d + 1e-3) ** 4, name) for d, name in chosen]
        total = sum(w for w, _ in weights)
        for w, name in weights:
            groups[name].add([vertex.index], w / total, "REPLACE")
    modifier = mesh_obj.modifiers.new("armature", "ARMATURE")
    modifier.object = armature_obj
    mesh_obj.parent = armature_obj
    return modifier


# A humanoid of capsules, about 1.45 units tall standing on z = 0 facing -Y (towards the front
# cameras). Bones point from joint to joint so a pose is a rotation per bone.
HUMANOID_BONES = [
    ("hips", (0, 0, 0.72), (0, 0, 0.9), None),
    ("spine", (0, 0, 0.9), (0, 0, 1.2), "hips"),
    ("head", (0, 0, 1.2), (0, 0, 1.45), "spine"),
    ("upper_arm.L", (0.19, 0, 1.16), (0.45, 0, 1.16), "spine"),
    ("forearm.L", (0.45, 0, 1.16), (0.7, 0, 1.16), "upper_arm.L"),
    ("upper_arm.R", (-0.19, 0, 1.16), (-0.45, 0, 1.16), "spine"),
    ("forearm.R", (-0.45, 0, 1.16), (-0.7, 0, 1.16), "upper_arm.R"),
    ("thigh.L", (0.1, 0, 0.72), (0.1, 0, 0.38), "hips"),
    ("shin.L", (0.1, 0, 0.38), (0.1, 0, 0.04), "thigh.L"),
    ("thigh.R", (-0.1, 0, 0.72), (-0.1, 0, 0.38), "hips"),
    ("shin.R", (-0.1, 0, 0.38), (-0.1, 0, 0.04), "thigh.R"),
]


def capsule(head, tail, radius, segments=12, rings=6):
    """A tapered cylinder from `head` to `tail`, subdivided along its length so it can bend."""
    head, tail = Vector(head), Vector(tail)
    axis = tail - head
    part = cylinder(radius, radius * 0.85, axis.length, segments=segments, rings=rings)
    rotation = axis.to_track_quat("Z", "Y").to_matrix().to_4x4()
    return transformed(part, Matrix.Translation((head + tail) / 2) @ rotation)


def vertex_normals(mesh):
    """Unit vertex normals of `mesh` (its rest shape): each face's unit normal weighted by the
    corner's angle, as Blender weights them, summed in an order that does not depend on how the
    mesh is numbered. Blender 3.4 sums them over threads in an order that changes from run to
    run, and bmesh numbers the faces of its primitives differently from run to run (see
    sample_surface_points), so `vertex.normal` can differ in its last bits between two runs of
    the same script, and so would a shape key built on it. Here each face starts at its
    smallest corner, and each vertex's terms are summed sorted."""
    co = [v.co.copy() for v in mesh.vertices]
    terms = [[] for _ in co]
    for face in mesh.polygons:
        ids = list(face.vertices)
        first = min(range(len(ids)), key=lambda k: tuple(co[ids[k]]))
        ids = ids[first:] + ids[:first]
        normal = Vector((0.0, 0.0, 0.0))  # Newell's method
        for a, b in zip(ids, ids[1:] + ids[:1]):
            normal += co[a].cross(co[b])
        if normal.length == 0.0:
            continue
        normal.normalize()
        for k, v in enumerate(ids):
            to_prev = co[ids[k - 1]] - co[v]
            to_next = co[ids[(k + 1) % len(ids)]] - co[v]
            if to_prev.length > 0.0 and to_next.length > 0.0:
                terms[v].append(tuple(normal * to_prev.angle(to_next)))
    normals = []
    for vertex_terms in terms:
        total = Vector((0.0, 0.0, 0.0))
        for term in sorted(vertex_terms):
            total += Vector(term)
        normals.append(total.normalized() if total.length > 0.0 else Vector((0.0, 0.0, 1.0)))
    return normals


def humanoid(name, material, location=(0, 0, 0), bulk=1.0):
    """Returns (armature object, body mesh object). `bulk` thickens every limb (the mutant)."""
    radius = {"hips": 0.15, "spine": 0.17, "upper_arm": 0.055, "forearm": 0.045,
              "thigh": 0.075, "shin": 0.06}
    parts = []
    for bone_name, head, tail, _ in HUMANOID_BONES:
        base = bone_name.split(".")[0]
        if base != "head":
            parts.append(capsule(head, tail, radius[base] * bulk))
    parts.append(transformed(uv_sphere(0.11 * bulk, 16, 10), Matrix.Translation((0, 0, 1.33))))
    for x in (0.72, -0.72):  # hands
        parts.append(transformed(uv_sphere(0.05 * bulk, 10, 6), Matrix.Translation((x, 0, 1.16))))
    for x in (0.1, -0.1):  # feet
        parts.append(transformed(box((0.09, 0.2, 0.05), (1, 2, 1)),
                                 Matrix.Translation((x, -0.05, 0.025))))
    body = mesh_object(name + "_body", merge(parts), material)
    rig = build_armature(name + "_rig", HUMANOID_BONES, location)
    skin(body, rig, HUMANOID_BONES)
    return rig, body


AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def pose(rig, rotations):
    """rotations: bone name -> [(axis, degrees), ...] about the armature's own X, Y or Z axis (the
    figures face -Y with +Z up), applied in order, relative to the parent bone. Working in the
    armature's axes rather than each bone's rest axes keeps the poses readable."""
    for bone_name, turns in rotations.items():
        pose_bone = rig.pose.bones[bone_name]
        to_bone = pose_bone.bone.matrix_local.to_3x3().transposed()
        rotation = Quaternion()
        for axis, degrees in turns:
            rotation = Quaternion(to_bone @ Vector(AXES[axis]), math.radians(degrees)) @ rotation
        pose_bone.rotation_mode = "QUATERNION"
        pose_bone.rotation_quaternion = rotation


# ---------------------------------------------------------------------------------------------
# Cameras


def camera(name, angle_x):
    data = bpy.data.cameras.new(name)
    data.sensor_fit = "HORIZONTAL"  # camera_angle_x is the horizontal field of view at any aspect
    data.sensor_width = 36.0
    data.angle_x = angle_x
    data.clip_start = 0.05
    data.clip_end = 100.0
    return link(bpy.data.objects.new(name, data))


def place_camera(obj, target, azimuth_deg, elevation_deg, distance):
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    offset = Vector((math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)))
    obj.location = Vector(target) + offset * distance
    aim(obj, target)


# ---------------------------------------------------------------------------------------------
# Surface sampling for point3d.ply


def sample_surface_points(count, rng):
    """`count` points spread over every rendered mesh by area, from the evaluated (deformed)
    meshes at the current time, with their material's colour. Returns a flat float32 array of
    x, y, z, r, g, b per point.

    Reproducible by construction: bmesh's primitives number their vertices and faces differently
    from run to run, so every polygon is rotated to start at its smallest corner, fanned into
    triangles from there, and the triangles are sorted by their corners before sampling."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    triangles = []
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH" or obj.hide_render or obj.get("hdr4d_no_points"):
            continue
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        world = evaluated.matrix_world
        colors = [list(slot.material.get("hdr4d_color", (0.5, 0.5, 0.5))) if slot.material
                  else [0.5, 0.5, 0.5] for slot in evaluated.material_slots] or [[0.5] * 3]
        for polygon in mesh.polygons:
            corners = [tuple(world @ mesh.vertices[i].co) for i in polygon.vertices]
            first = min(range(len(corners)), key=lambda i: corners[i])
            corners = corners[first:] + corners[:first]
            color = tuple(colors[min(polygon.material_index, len(colors) - 1)][:3])
            for j in range(1, len(corners) - 1):
                triangles.append((corners[0], corners[j], corners[j + 1], color))
        evaluated.to_mesh_clear()
    triangles.sort()
    areas = [(Vector(b) - Vector(a)).cross(Vector(c) - Vector(a)).length / 2
             for a, b, c, _ in triangles]
    if not triangles or sum(areas) <= 0:
        raise RuntimeError("the scene has no surface to sample points from")
    chosen = rng.choices(range(len(triangles)), weights=areas, k=count)
    out = array("f")
    for index in chosen:
        a, b, c, color = triangles[index]
        a, b, c = Vector(a), Vector(b), Vector(c)
        u, v = rng.random(), rng.random()
        if u + v > 1:
            u, v = 1 - u, 1 - v
        p = a + (b - a) * u + (c - a) * v
        out.extend((p.x, p.y, p.z, *[min(1.0, max(0.0, x)) for x in color]))
    return out


def smooth_pulse(t, center, width):
    """0..1 bump around `center` (a cosine window `width` wide): flashes and blinks."""
    x = (t - center) / width
    return 0.5 * (1 + math.cos(math.pi * x * 2)) if abs(x) < 0.5 else 0.0


def new_rng(seed, salt):
    return random.Random(f"{seed}:{salt}")
