"""Render one shard: build the scene from files Rust wrote, render every frame, save EXRs.

Run by egogen (`python render_shard.py SPEC.json` with PyPI bpy, or
`blender --background --python-exit-code 1 --python render_shard.py -- SPEC.json`).
Thin on purpose: every number comes from the spec (see src/render/protocol.rs): the scene, the
bodies, the obstacles, the objects people carry and the scene objects they move (chairs pulled
out), each with its keys. Per camera it renders the RGB image of every frame (Cycles, camera + deformation motion blur) when the spec
asks for colour, and then the ground truth of every frame (motion blur off, 1 sample at the
pixel centre) with the spec's passes (position, normal, object index, motion vectors) when it
asks for any. The ground truth runs on a timeline scaled by `ground_truth_frame_step`, so that
motion vectors reach the previous and next *saved* frame. Each file is written to
`<output>.partial.exr` and renamed, so a killed worker never leaves a half-written file under
the final name. Prints one `EGOGEN_DONE <path>` line per finished file, and
`EGOGEN_TIMING <stage> <seconds>` lines saying where the time goes (`ready` once `bpy` is
imported; then scene import, camera set-up, each frame's scene update and render; the
supervisor adds them up per attempt, docs/RENDERING.md "Where a frame's time goes").
`render_shard.py --check-device gpu` only says which GPU Blender would render on (exit 0) or
why it cannot (exit 3, `EGOGEN_SETUP_FAILED`): egogen runs it before it stages a take.
`render_shard.py --serve TAKE_DIR` is a long-lived worker: it builds the scene once and renders
shard after shard of one take, each named on a line of its standard input (see `serve`).
`render_shard.py --outfit-sheet SHEET.json` renders `egogen body outfits`' people with the
bodies' own materials (see `outfit_sheet`).
"""
import json
import math
import os
import sys
import time

import bpy
import bmesh  # after bpy: the bpy wheel's bmesh is there once bpy is loaded
import numpy as np
from mathutils import Matrix, Quaternion, Vector


def script_args():
    """The script's own arguments: after `--` under a Blender executable, else all of them."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]


def load_spec():
    args = script_args()
    if len(args) != 1:
        sys.exit("usage: render_shard.py SPEC.json | --serve TAKE_DIR | --check-device gpu")
    with open(args[0]) as f:
        return json.load(f)


def add_body(scene, body):
    """A body mesh with the PC2 vertex cache attached; vertex order is the cache's."""
    obj = body_object(body, np.load(body["vertices_npy"]))
    obj.pass_index = body["pass_index"]
    scene.collection.objects.link(obj)
    cache = obj.modifiers.new("egogen_cache", "MESH_CACHE")
    cache.cache_format = "PC2"
    cache.filepath = body["pc2"]
    cache.interpolation = "LINEAR"
    # The cache's samples played back by keys (it may hold the rendered times only).
    cache.play_mode = "CUSTOM"
    cache.time_mode = "FRAME"
    key_cache(obj, body["cache_keys"], 1)
    cache.forward_axis = "POS_Y"
    cache.up_axis = "POS_Z"
    obj.cycles.use_motion_blur = True
    obj.cycles.use_deform_motion = True
    # EGOGEN_BLENDER_MOTION_STEPS overrides the spec's (for `cargo bench --bench render_cost`).
    obj.cycles.motion_steps = int(os.environ.get("EGOGEN_BLENDER_MOTION_STEPS", body["motion_steps"]))
    return obj


def body_object(body, vertices):
    """A smooth-shaded body mesh of `vertices` and the spec's faces, with its UVs, skin and
    outfit (not linked to a scene)."""
    faces = np.load(body["faces_npy"])
    mesh = bpy.data.meshes.new(body["name"])
    mesh.from_pydata(vertices.tolist(), [], faces.tolist())
    mesh.update()
    for poly in mesh.polygons:
        poly.use_smooth = True
    if body.get("uvs_npy"):
        add_uv_layer(mesh, np.load(body["uvs_npy"]), body["uvs_npy"])
    material = skin_material(body["name"] + "_skin", body["skin"],
                             body.get("skin_regions", []), body.get("skin_detail"))
    if body.get("outfit"):
        add_outfit_attributes(mesh, body["outfit"])
        # Garment codes only where the segmentation is rendered (where the parts are).
        codes = body["outfit"]["slots"] if body.get("parts_npy") else None
        garment = dress(material, body["outfit"]["outfit"], codes)
        if garment is not None:
            add_aov_output(material, GARMENT_AOV, garment)
    # EGOGEN_BLENDER_PART_AOV=0 leaves the parts out (for `cargo bench --bench render_cost`:
    # their `segmentation.part` then reads 0).
    if body.get("parts_npy") and os.environ.get("EGOGEN_BLENDER_PART_AOV") != "0":
        add_part_output(mesh, material, body["parts_npy"])
    mesh.materials.append(material)
    return bpy.data.objects.new(body["name"], mesh)


def key_cache(obj, keys, frame_step):
    """Plays a sparse cache: sample `key[1]` at frame `key[0] / frame_step`, linearly between
    keys (held before the first and after the last)."""
    obj.animation_data_clear()
    cache = obj.modifiers["egogen_cache"]
    path = 'modifiers["egogen_cache"].eval_frame'
    for frame, sample in keys:
        cache.eval_frame = sample
        obj.keyframe_insert(path, frame=frame / frame_step)
    for fcurve in action_fcurves(obj.animation_data.action):
        for point in fcurve.keyframe_points:
            point.interpolation = "LINEAR"


def add_uv_layer(mesh, uvs, path):
    """The body's UV map, one (u, v) per triangle corner in face order (= Blender's loops)."""
    if uvs.shape != (len(mesh.loops), 2):
        sys.exit(f"{path}: expected float32 ({len(mesh.loops)}, 2) corner UVs for "
                 f"{len(mesh.polygons)} triangles, found {uvs.dtype} {uvs.shape}")
    layer = mesh.uv_layers.new(name="UVMap")
    layer.data.foreach_set("uv", np.ascontiguousarray(uvs, dtype=np.float32).ravel())


def socket(sockets, identifier):
    return next(s for s in sockets if s.identifier == identifier)


def uv_image(nodes, links, uv, path):
    """A grey image (data, not colour) in the body's UV layout, read at `uv`'s coordinates."""
    image = bpy.data.images.load(path, check_existing=True)
    image.colorspace_settings.name = "Non-Color"
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Linear"
    links.new(uv.outputs["UV"], texture.inputs["Vector"])
    return texture


def skin_material(name, skin, regions, detail=None):
    """Principled BSDF skin: the tone's base colour, each region's colour mixed in through its
    mask (in the body's UV layout), mottled by noise on the rest-pose (Generated) coordinates,
    which stay on the skin as the vertex cache deforms the mesh, and multiplied by twice the
    detail map (the relative lightness of a skin albedo in the same layout) when there is one."""
    mat = bpy.data.materials.new(name)
    mat.diffuse_color = (*skin["base_rgb"], 1.0)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = skin["roughness"]
    bsdf.inputs["Subsurface Weight"].default_value = skin["subsurface_weight"]
    bsdf.inputs["Subsurface Radius"].default_value = (1.0, 0.2, 0.1)
    bsdf.inputs["Subsurface Scale"].default_value = 0.01
    coords = nodes.new("ShaderNodeTexCoord")
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 60.0
    noise.inputs["Detail"].default_value = 4.0
    links.new(coords.outputs["Generated"], noise.inputs["Vector"])
    # factor = 1 + mottle * (2 * noise - 1)
    centred = nodes.new("ShaderNodeMath")
    centred.operation = "MULTIPLY_ADD"
    centred.inputs[1].default_value = 2.0 * skin["mottle"]
    centred.inputs[2].default_value = 1.0 - skin["mottle"]
    links.new(noise.outputs["Fac"], centred.inputs[0])
    colour = nodes.new("ShaderNodeVectorMath")
    colour.operation = "MULTIPLY"
    colour.inputs[0].default_value = skin["base_rgb"]
    links.new(centred.outputs["Value"], colour.inputs[1])
    links.new(colour.outputs["Vector"], bsdf.inputs["Base Color"])
    uv = None
    if detail or regions:
        uv = nodes.new("ShaderNodeUVMap")
        uv.uv_map = "UVMap"
    if detail:
        texture = uv_image(nodes, links, uv, detail)
        twice = nodes.new("ShaderNodeMath")
        twice.operation = "MULTIPLY"
        twice.inputs[1].default_value = 2.0
        links.new(texture.outputs["Color"], twice.inputs[0])
        detailed = nodes.new("ShaderNodeVectorMath")
        detailed.operation = "MULTIPLY"
        links.new(colour.outputs["Vector"], detailed.inputs[0])
        links.new(twice.outputs["Value"], detailed.inputs[1])
        links.new(detailed.outputs["Vector"], bsdf.inputs["Base Color"])
    if regions:
        base, rough = None, None  # the outputs carrying colour and roughness so far
        for region in regions:
            paint = region["paint"]
            mask = uv_image(nodes, links, uv, region["mask"])
            mix = nodes.new("ShaderNodeMix")
            mix.data_type = "RGBA"
            links.new(mask.outputs["Color"], socket(mix.inputs, "Factor_Float"))
            if base is None:
                socket(mix.inputs, "A_Color").default_value = (*skin["base_rgb"], 1.0)
            else:
                links.new(base, socket(mix.inputs, "A_Color"))
            socket(mix.inputs, "B_Color").default_value = (*paint["rgb"], 1.0)
            base = socket(mix.outputs, "Result_Color")
            mixr = nodes.new("ShaderNodeMix")
            mixr.data_type = "FLOAT"
            links.new(mask.outputs["Color"], socket(mixr.inputs, "Factor_Float"))
            if rough is None:
                socket(mixr.inputs, "A_Float").default_value = skin["roughness"]
            else:
                links.new(rough, socket(mixr.inputs, "A_Float"))
            socket(mixr.inputs, "B_Float").default_value = paint["roughness"]
            rough = socket(mixr.outputs, "Result_Float")
        links.new(base, colour.inputs[0])
        links.new(rough, bsdf.inputs["Roughness"])
    return mat


def add_outfit_attributes(mesh, outfit):
    """Each garment slot's signed distance (m, positive on the garment) and the rest position
    as point attributes (`egogen_<slot>`, `egogen_rest`): they stay on the skin as the vertex
    cache moves the body."""
    path = outfit["fields_npy"]
    fields = np.load(path)
    slots = outfit["slots"]
    if fields.shape != (len(mesh.vertices), len(slots) + 3):
        sys.exit(f"{path}: expected float32 ({len(mesh.vertices)}, {len(slots) + 3}) garment "
                 f"fields, found {fields.dtype} {fields.shape}")
    fields = np.ascontiguousarray(fields, dtype=np.float32)
    for k, slot in enumerate(slots):
        attribute = mesh.attributes.new("egogen_" + slot, "FLOAT", "POINT")
        attribute.data.foreach_set("value", np.ascontiguousarray(fields[:, k]))
    rest = mesh.attributes.new("egogen_rest", "FLOAT_VECTOR", "POINT")
    rest.data.foreach_set("vector", np.ascontiguousarray(fields[:, len(slots):]).ravel())


def add_part_output(mesh, material, path):
    """Each face's body part (a hand, a forearm, the rest) as a face attribute (constant over
    the face: never a blend of two parts), written by the material to the `part` AOV: the
    ground truth's `segmentation.part` channel."""
    parts = np.load(path)
    if parts.shape != (len(mesh.polygons), 1):
        sys.exit(f"{path}: expected float32 ({len(mesh.polygons)}, 1) body parts, found "
                 f"{parts.dtype} {parts.shape}")
    attribute = mesh.attributes.new("egogen_part", "FLOAT", "FACE")
    attribute.data.foreach_set("value", np.ascontiguousarray(parts[:, 0], dtype=np.float32))
    nodes, links = material.node_tree.nodes, material.node_tree.links
    read = nodes.new("ShaderNodeAttribute")
    read.attribute_type = "GEOMETRY"
    read.attribute_name = "egogen_part"
    add_aov_output(material, PART_AOV, read.outputs["Fac"])


def add_aov_output(material, name, value):
    """Writes `value` (a socket or a number) to the AOV `name` (registered on the view layer
    when the scene is built)."""
    out = material.node_tree.nodes.new("ShaderNodeOutputAOV")
    out.aov_name = name
    Nodes(material).feed(out.inputs["Value"], value)


# The ground truth's AOVs holding each pixel's body part and garment.
PART_AOV = "part"
GARMENT_AOV = "garment"


def linked_or_value(target):
    """What feeds a node input: the linked socket, or its value."""
    if target.is_linked:
        return target.links[0].from_socket
    value = target.default_value
    return tuple(value) if hasattr(value, "__len__") else value


def fabric_colour(n, g, rest):
    """A garment's colour socket: its pattern (plain, stripes, checks, print) in the body's rest
    coordinates (m), and its fabric's weave drawn in colour alone (no bump: the Normal pass is
    ground truth)."""
    base, accent = rgba(g["base_rgb"]), rgba(g["accent_rgb"])
    s, p, fabric = g["scale_m"], g["pattern"], g["fabric"]

    def bands(direction, size):
        wave = n.add("ShaderNodeTexWave", [("Vector", rest), ("Scale", 1.0 / size)],
                     wave_type="BANDS", bands_direction=direction).outputs["Fac"]
        return n.ramp(wave, 0.45, 0.55)

    if g["slot"] == "hair":
        # Strands: noise stretched along the body's height.
        along = n.add("ShaderNodeVectorMath", [(0, rest), (1, (400.0, 25.0, 400.0))],
                      operation="MULTIPLY").outputs["Vector"]
        strands = n.add("ShaderNodeTexNoise", [("Vector", along), ("Scale", 1.0),
                                               ("Detail", 6.0)]).outputs["Fac"]
        return n.mix("RGBA", n.ramp(strands, 0.3, 0.7), accent, base)
    if p == "stripes":
        colour = n.mix("RGBA", bands("Y", s), base, accent)
    elif p == "checks":
        across = n.math("MAXIMUM", bands("X", s), bands("Z", s))
        colour = n.mix("RGBA", n.math("MULTIPLY", n.math("ADD", across, bands("Y", s)), 0.5),
                       base, accent)
    elif p == "print":
        dots = n.add("ShaderNodeTexVoronoi", [("Vector", rest), ("Scale", 1.0 / s),
                                              ("Randomness", 0.8)]).outputs["Distance"]
        colour = n.mix("RGBA", n.ramp(dots, 0.3, 0.25), base, accent)
    else:
        colour = n.mix("RGBA", n.math("MULTIPLY", noise(n, rest, 0.05), 0.35), base, accent)
    if fabric == "denim":
        twill = n.add("ShaderNodeTexWave", [("Vector", rest), ("Scale", 1.0 / 0.0025)],
                      wave_type="BANDS", bands_direction="DIAGONAL").outputs["Fac"]
        weave = n.math("MULTIPLY", twill, 0.25)
        light = rgba([min(1.0, 1.6 * c + 0.08) for c in g["base_rgb"]])
    elif fabric == "knit":
        weave = n.math("MULTIPLY", bands("X", 0.005), 0.2)
        light = rgba(g["base_rgb"], 0.7)
    elif fabric == "leather":
        grain = n.add("ShaderNodeTexVoronoi", [("Vector", rest), ("Scale", 1.0 / 0.003)]).outputs["Distance"]
        weave = n.math("MULTIPLY", grain, 0.2)
        light = rgba(g["base_rgb"], 1.25)
    else:
        size = {"wool": 0.003, "cotton": 0.0015}.get(fabric, 0.001)
        weave = n.math("MULTIPLY", noise(n, rest, size, 2.0), {"wool": 0.3}.get(fabric, 0.15))
        light = rgba(g["base_rgb"], 0.75)
    return n.mix("RGBA", weave, colour, light)


def dress(mat, outfit, slots=None):
    """Paints the outfit over the skin material `mat`: each garment, lowest first, where its
    signed distance is positive (an edge 3 mm wide across triangles), hems darkened within
    6 mm of the edge, with the fabric's roughness and sheen; the skin's subsurface scattering
    only where the skin shows. Given the slots in their code order, returns a socket holding
    the garment on top at each point (its slot's place in `slots` + 1; 0 the skin): the
    ground truth's `segmentation.garment`."""
    n = Nodes(mat)
    bsdf = n.nodes["Principled BSDF"]
    colour = linked_or_value(bsdf.inputs["Base Color"])
    rough = linked_or_value(bsdf.inputs["Roughness"])
    sheen, covered, code = 0.0, 0.0, 0.0
    rest = n.add("ShaderNodeAttribute", attribute_name="egogen_rest").outputs["Vector"]
    for g in outfit["garments"]:
        f = n.add("ShaderNodeAttribute", attribute_name="egogen_" + g["slot"]).outputs["Fac"]
        if slots is not None:
            # Where the colour's edge is: the middle of the cover's ramp.
            code = n.mix("FLOAT", n.math("GREATER_THAN", f, 0.0), code,
                         float(slots.index(g["slot"]) + 1))
        cover = n.math("MULTIPLY", n.ramp(f, -0.0015, 0.0015), g["cover"])
        fabric = fabric_colour(n, g, rest)
        if g["slot"] != "hair":
            hem = n.math("MULTIPLY_ADD", n.ramp(f, 0.0, 0.006), 0.25, 0.75)
            fabric = n.add("ShaderNodeVectorMath", [(0, fabric), ("Scale", hem)],
                           operation="SCALE").outputs["Vector"]
        colour = n.mix("RGBA", cover, colour, fabric)
        rough = n.mix("FLOAT", cover, rough, g["roughness"])
        sheen = n.mix("FLOAT", cover, sheen, g["sheen"])
        covered = n.math("MAXIMUM", covered, cover)
    n.feed(bsdf.inputs["Base Color"], colour)
    n.feed(bsdf.inputs["Roughness"], rough)
    n.feed(bsdf.inputs["Sheen Weight"], sheen)
    skin_sss = bsdf.inputs["Subsurface Weight"].default_value
    n.feed(bsdf.inputs["Subsurface Weight"], n.mix("FLOAT", covered, skin_sss, 0.0))
    return code if slots is not None else None


def add_ceiling(scene, ceiling):
    """A light grey rectangle facing down at the top of the walls (a scene without a ceiling)."""
    (x0, y0), (x1, y1), z = ceiling["min_xy"], ceiling["max_xy"], ceiling["z_m"]
    mesh = bpy.data.meshes.new("egogen_ceiling")
    # Wound clockwise seen from above: the normal points down, into the rooms.
    mesh.from_pydata([(x0, y0, z), (x0, y1, z), (x1, y1, z), (x1, y0, z)], [], [(0, 1, 2, 3)])
    mesh.update()
    mat = bpy.data.materials.new("egogen_ceiling_material")
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.8, 0.78, 1.0)
    mesh.materials.append(mat)
    obj = bpy.data.objects.new("egogen_ceiling", mesh)
    scene.collection.objects.link(obj)


def add_obstacle(scene, ob):
    """A box (an `[[obstacles]]` entry) standing on the floor, moving linearly between keys."""
    sx, sy, sz = (0.5 * v for v in ob["size_m"])
    verts = [(x, y, z) for x in (-sx, sx) for y in (-sy, sy) for z in (-sz, sz)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh = bpy.data.meshes.new(ob["name"])
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    mat = bpy.data.materials.new(ob["name"] + "_material")
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.25, 0.32, 0.45, 1.0)
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(ob["name"], mesh)
    obj.pass_index = ob["pass_index"]
    obj.rotation_euler = (0.0, 0.0, ob["yaw_rad"])
    obj.cycles.use_motion_blur = True
    scene.collection.objects.link(obj)
    key_obstacle(obj, ob["keys"])
    return obj


def add_held_object(scene, ob):
    """A small object a person picks up (a `held_objects` entry): an upright cylinder of its
    size, centred on its origin, in one colour, posed by its keys."""
    sx, sy, sz = ob["size_m"]
    if ob["shape"] != "cylinder":
        sys.exit(f"held object {ob['name']}: shape {ob['shape']!r}, expected \"cylinder\"")
    mesh = bpy.data.meshes.new(ob["name"])
    bm = bmesh.new()
    bmesh.ops.create_cone(bm, cap_ends=True, segments=32, radius1=0.5 * sx,
                          radius2=0.5 * sx, depth=sz)
    bm.to_mesh(mesh)
    bm.free()
    for poly in mesh.polygons:
        poly.use_smooth = abs(poly.normal.z) < 0.5
    mat = bpy.data.materials.new(ob["name"] + "_material")
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*ob["colour_rgb"], 1.0)
    bsdf.inputs["Roughness"].default_value = 0.35
    mesh.materials.append(mat)
    obj = bpy.data.objects.new(ob["name"], mesh)
    obj.pass_index = ob["pass_index"]
    obj.rotation_mode = "QUATERNION"
    obj.cycles.use_motion_blur = True
    scene.collection.objects.link(obj)
    key_pose(obj, ob["keys"])
    return obj


def linear_keys(obj, keys):
    """Linear interpolation between `obj`'s keys, where it has more than one (Bezier would
    ease in and out; takes move things at the speed their keys say)."""
    if len(keys) > 1:
        for fcurve in action_fcurves(obj.animation_data.action):
            for point in fcurve.keyframe_points:
                point.interpolation = "LINEAR"


def key_pose(obj, keys, frame_step=1):
    """Location and rotation keys at `key.frame / frame_step`, linear in between (a held
    object's; the camera's are keyed the same way)."""
    obj.animation_data_clear()
    for key in keys:
        obj.location = Vector(key["location"])
        obj.rotation_quaternion = Quaternion(key["rotation_wxyz"])
        if len(keys) > 1:
            obj.keyframe_insert("location", frame=key["frame"] / frame_step)
            obj.keyframe_insert("rotation_quaternion", frame=key["frame"] / frame_step)
    linear_keys(obj, keys)


def key_moved(obj, base, keys, frame_step=1):
    """An object of the imported scene that people move (a `moved_objects` entry): its world
    matrix `base` turned by each key's `rotation_wxyz` (where given) about the world's origin
    and moved by its `centre`, location (and rotation) keys at `key.frame / frame_step`,
    linear in between."""
    obj.animation_data_clear()
    turned = any("rotation_wxyz" in key for key in keys)
    if turned:
        obj.rotation_mode = "QUATERNION"
    for key in keys:
        motion = Matrix.Translation(Vector(key["centre"]))
        if "rotation_wxyz" in key:
            motion = motion @ Quaternion(key["rotation_wxyz"]).to_matrix().to_4x4()
        obj.matrix_world = motion @ base
        if len(keys) > 1:
            obj.keyframe_insert("location", frame=key["frame"] / frame_step)
            if turned:
                obj.keyframe_insert("rotation_quaternion", frame=key["frame"] / frame_step)
    linear_keys(obj, keys)


def key_obstacle(obj, keys, frame_step=1):
    """Location keys at `key.frame / frame_step` (the ground truth's scaled timeline)."""
    obj.animation_data_clear()
    for key in keys:
        obj.location = Vector(key["centre"])
        if len(keys) > 1:
            obj.keyframe_insert("location", frame=key["frame"] / frame_step)
    linear_keys(obj, keys)


def action_fcurves(action):
    """An action's F-curves (Blender 4.4+ keeps them in layers, strips and channel bags)."""
    if getattr(action, "layers", None):
        return [fc for layer in action.layers for strip in layer.strips
                for bag in strip.channelbags for fc in bag.fcurves]
    return list(action.fcurves)


def add_world_hdri(world, hdri):
    """World light from an HDRI shipped with Blender (datafiles/studiolights/world), turned
    about the vertical and scaled."""
    folder = bpy.utils.system_resource("DATAFILES", path="studiolights/world")
    path = os.path.join(folder or "", hdri["name"] + ".exr")
    if not os.path.isfile(path):
        raise RuntimeError(f"HDRI {hdri['name']!r}: {path} not found in this Blender")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes["Background"]
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, hdri["rotation_rad"])
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(path, check_existing=True)
    links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], background.inputs["Color"])
    background.inputs["Strength"].default_value = hdri["strength"]


GPU_BACKENDS = ("OPTIX", "CUDA", "HIP", "ONEAPI", "METAL")


def find_gpu():
    """The first GPU backend Blender finds a device for, with the devices' names, set up in the
    preferences for rendering; RuntimeError naming what it looked for when there is none."""
    prefs = bpy.context.preferences.addons["cycles"].preferences
    for backend in GPU_BACKENDS:
        try:
            prefs.compute_device_type = backend
        except TypeError:  # not built into this Blender
            continue
        prefs.refresh_devices()
        gpus = [d for d in prefs.devices if d.type == backend]
        if gpus:
            for d in prefs.devices:
                d.use = d.type == backend
            return backend, ", ".join(d.name for d in gpus)
    raise RuntimeError(
        'render.device = "gpu", but Blender found no GPU (looked for '
        + ", ".join(GPU_BACKENDS)
        + '); use device = "cpu" on this machine'
    )


def set_device(scene, device):
    """Cycles on the CPU, or on the first GPU backend that Blender finds a device for."""
    if device == "cpu":
        scene.cycles.device = "CPU"
        return
    backend, names = find_gpu()
    scene.cycles.device = "GPU"
    # What Cycles on a GPU wants: the denoiser on the GPU too (OIDN 2 runs on CUDA, HIP,
    # oneAPI and Metal devices; Blender falls back to the CPU where it cannot), and tiles as
    # large as the frame (Blender's default 2048 px covers every Aria camera at full size).
    # Persistent data is on for every device (above).
    if hasattr(scene.cycles, "denoising_use_gpu"):
        scene.cycles.denoising_use_gpu = True
    scene.cycles.use_auto_tile = True
    scene.cycles.tile_size = max(scene.cycles.tile_size, 2048)
    print(f"egogen: rendering on {backend}: {names}", file=sys.stderr, flush=True)


def check_device(device):
    """`render_shard.py --check-device gpu`: says which GPU Blender would render on and exits 0,
    or why it cannot (exit EXIT_SETUP_FAILED); run by egogen before a take is staged."""
    if device != "gpu":
        sys.exit(f"--check-device {device}: expected gpu")
    try:
        backend, names = find_gpu()
    except RuntimeError as e:
        print(f"EGOGEN_SETUP_FAILED {e}", file=sys.stderr, flush=True)
        sys.exit(EXIT_SETUP_FAILED)
    print(f"egogen: Blender renders on {backend}: {names}", file=sys.stderr, flush=True)


def import_scene_file(path, up_axis, unit_m=1.0):
    """Imports the scene with Blender's importer for its extension, turned so that z is up
    (Rust says which axis of the file is up, as its own loader reads it) and scaled to metres
    by `unit_m` (metres per unit of the file)."""
    ext = os.path.splitext(path)[1].lower()
    axes = {"z": ("Y", "Z"), "y": ("NEGATIVE_Z", "Y")}[up_axis]
    # What the importer leaves to do: the scale to metres and, for a glTF file that is not y up
    # as the specification says, turning back what the importer turned.
    fix = Matrix.Scale(unit_m, 4)
    if ext in (".glb", ".gltf"):
        # glTF is y up by specification; the importer turns (x, y, z) to (x, -z, y).
        bpy.ops.import_scene.gltf(filepath=path)
        if up_axis == "z":
            fix = fix @ Matrix.Rotation(-math.pi / 2, 4, "X")
    elif ext == ".obj":
        # Objects and groups each become an object, as the Rust loader splits them; the MTL's
        # materials and image textures come with them.
        bpy.ops.wm.obj_import(
            filepath=path,
            forward_axis=axes[0],
            up_axis=axes[1],
            use_split_objects=True,
            use_split_groups=True,
        )
    elif ext == ".ply":
        bpy.ops.wm.ply_import(filepath=path, forward_axis=axes[0], up_axis=axes[1])
    else:
        raise RuntimeError(f"unsupported scene file {path}")
    if fix != Matrix.Identity(4):
        for obj in bpy.context.scene.objects:
            if obj.parent is None:
                obj.matrix_world = fix @ obj.matrix_world
    for obj in bpy.context.scene.objects:
        if obj.type == "MESH" and not obj.data.materials and obj.data.color_attributes:
            obj.data.materials.append(vertex_colour_material(obj.data.color_attributes[0].name))


def vertex_colour_material(attribute):
    """A diffuse material showing a mesh's vertex colours (a scan's PLY has no other)."""
    mat = bpy.data.materials.new(f"egogen_vertex_colour_{attribute}")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    colour = nodes.new("ShaderNodeVertexColor")
    colour.layer_name = attribute
    bsdf = nodes["Principled BSDF"]
    mat.node_tree.links.new(colour.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.8
    return mat


def split_scene(split):
    """Splits the one mesh a scan's PLY imports as into the scene's objects: each face goes to
    the object Rust's loader put it in (`split["face_objects"]`: an index into
    `split["names"]` per face of the file, in file order, as Blender keeps it). Each part is
    built from the imported mesh's arrays (positions, corners, colour attributes, texture
    coordinates, flat shading), so a scan of 10^6 triangles splits in about a second (Blender's own
    separate-by-material took 6.9 s on one, docs/SCENES.md)."""
    import numpy as np

    names = split["names"]
    faces = np.load(split["face_objects"]).reshape(-1).astype(np.int64)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if len(meshes) != 1 or len(meshes[0].data.polygons) != len(faces):
        raise RuntimeError(
            f"the scene imported as {len(meshes)} meshes with "
            f"{[len(o.data.polygons) for o in meshes]} faces; its object ids name {len(faces)}"
        )
    obj = meshes[0]
    mesh = obj.data
    material = mesh.materials[0] if mesh.materials else None
    nv, nl, nf = len(mesh.vertices), len(mesh.loops), len(mesh.polygons)
    co = np.empty(nv * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    loop_vertex = np.empty(nl, np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    loop_start = np.empty(nf, np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    loop_total = np.empty(nf, np.int32)
    mesh.polygons.foreach_get("loop_total", loop_total)
    colours = []
    for ca in mesh.color_attributes:
        n = nv if ca.domain == "POINT" else nl
        values = np.empty(n * 4, np.float32)
        ca.data.foreach_get("color", values)
        colours.append((ca.name, ca.data_type, ca.domain, values.reshape(-1, 4)))
    uv_layers = []
    for uv in mesh.uv_layers:
        values = np.empty(nl * 2, np.float32)
        uv.data.foreach_get("uv", values)
        uv_layers.append((uv.name, values.reshape(-1, 2)))
    sharp = None
    if "sharp_face" in mesh.attributes:
        sharp = np.empty(nf, bool)
        mesh.attributes["sharp_face"].data.foreach_get("value", sharp)
    matrix = obj.matrix_world.copy()
    collection = obj.users_collection[0]
    # Faces of no object (−1 or out of range) stay under the file's name.
    rest = len(names)
    slot = np.where((faces >= 0) & (faces < rest), faces, rest)
    part_names = names + [obj.name]
    bpy.data.objects.remove(obj)
    # Faces grouped by part once (stable: each part's faces in file order), not one scan of
    # every face per part: a scan of thousands of objects stays linear.
    order = np.argsort(slot, kind="stable")
    parts, first = np.unique(slot[order], return_index=True)
    ends = np.append(first[1:], len(order))
    for k, lo, hi in zip(parts, first, ends):
        sel = order[lo:hi]
        totals = loop_total[sel]
        starts = np.cumsum(totals) - totals
        loops = np.repeat(loop_start[sel], totals) + (
            np.arange(int(totals.sum())) - np.repeat(starts, totals)
        )
        used, corner = np.unique(loop_vertex[loops], return_inverse=True)
        name = part_names[k]
        part = bpy.data.meshes.new(name)
        part.vertices.add(len(used))
        part.vertices.foreach_set("co", co[used].ravel())
        part.loops.add(len(loops))
        part.loops.foreach_set("vertex_index", corner.astype(np.int32))
        part.polygons.add(len(sel))
        part.polygons.foreach_set("loop_start", starts.astype(np.int32))
        for cname, ctype, domain, values in colours:
            ca = part.color_attributes.new(cname, ctype, domain)
            ca.data.foreach_set(
                "color", (values[used] if domain == "POINT" else values[loops]).ravel()
            )
        for uv_name, values in uv_layers:
            part.uv_layers.new(name=uv_name).data.foreach_set("uv", values[loops].ravel())
        if sharp is not None:
            part.attributes.new("sharp_face", "BOOLEAN", "FACE").data.foreach_set(
                "value", sharp[sel]
            )
        part.update(calc_edges=True)
        if material is not None:
            part.materials.append(material)
        new = bpy.data.objects.new(name, part)
        new.matrix_world = matrix
        collection.objects.link(new)


class Nodes:
    """Builds a material's node tree: each method adds a node, links what it is given (a
    socket, or a value set as the input's default) and returns its output socket."""

    def __init__(self, mat):
        self.nodes, self.links = mat.node_tree.nodes, mat.node_tree.links

    def feed(self, target, value):
        if hasattr(value, "is_output"):
            self.links.new(value, target)
        else:
            target.default_value = value

    def add(self, kind, inputs=(), **props):
        node = self.nodes.new(kind)
        for key, value in props.items():
            setattr(node, key, value)
        for key, value in inputs:
            self.feed(node.inputs[key] if isinstance(key, int) else socket_named(node.inputs, key), value)
        return node

    def math(self, op, a, b=0.0, c=0.0):
        return self.add("ShaderNodeMath", [(0, a), (1, b), (2, c)], operation=op).outputs[0]

    def mix(self, data_type, factor, a, b):
        """`a` where factor is 0, `b` where it is 1 (FLOAT, VECTOR or RGBA)."""
        suffix = {"FLOAT": "Float", "VECTOR": "Vector", "RGBA": "Color"}[data_type]
        node = self.add("ShaderNodeMix", data_type=data_type)
        self.feed(socket(node.inputs, "Factor_Float"), factor)
        self.feed(socket(node.inputs, "A_" + suffix), a)
        self.feed(socket(node.inputs, "B_" + suffix), b)
        return socket(node.outputs, "Result_" + suffix)

    def ramp(self, value, lo, hi):
        """`value` mapped from [lo, hi] to [0, 1], clamped."""
        return self.add("ShaderNodeMapRange", [("Value", value), ("From Min", lo),
                                               ("From Max", hi)]).outputs["Result"]

    def grey(self, colour):
        return self.add("ShaderNodeRGBToBW", [("Color", colour)]).outputs["Val"]


def socket_named(sockets, name):
    """The first enabled socket called `name` (some nodes have several, one per data type)."""
    return next(s for s in sockets if s.name == name and s.enabled)


def rgba(rgb, k=1.0):
    return (*(min(1.0, c * k) for c in rgb), 1.0)


def planar_coordinates(n):
    """World position (m) on the plane a surface faces: (x, y) on floors and other surfaces
    facing up or down, (y, z) on walls facing ±x, (x, z) on walls facing ±y; so planks lie
    along floors and bricks stand upright on walls."""
    geometry = n.add("ShaderNodeNewGeometry")
    pos = n.add("ShaderNodeSeparateXYZ", [("Vector", geometry.outputs["Position"])]).outputs
    nrm = n.add("ShaderNodeSeparateXYZ", [("Vector", geometry.outputs["Normal"])]).outputs
    ax, ay, az = (n.math("ABSOLUTE", nrm[k]) for k in "XYZ")
    faces_x = n.math("GREATER_THAN", ax, ay)
    faces_up = n.math("GREATER_THAN", az, n.math("MAXIMUM", ax, ay))
    side_u = n.mix("FLOAT", faces_x, pos["X"], pos["Y"])
    u = n.mix("FLOAT", faces_up, side_u, pos["X"])
    v = n.mix("FLOAT", faces_up, pos["Z"], pos["Y"])
    return n.add("ShaderNodeCombineXYZ", [("X", u), ("Y", v)]).outputs["Vector"]


def noise(n, vector, size_m, detail=4.0, roughness=0.5):
    """Noise factor in [0, 1] with features about `size_m` across."""
    return n.add("ShaderNodeTexNoise", [("Vector", vector), ("Scale", 1.0 / size_m),
                                        ("Detail", detail), ("Roughness", roughness)]).outputs["Fac"]


def pattern_colour(n, m):
    """The base colour socket of one drawn material (`m`: a spec `materials` entry) and, for
    metal, its metallic value."""
    p, s = m["pattern"], m["scale_m"]
    base, accent = rgba(m["base_rgb"]), rgba(m["accent_rgb"])
    world = n.add("ShaderNodeNewGeometry").outputs["Position"]
    if p in ("wood_planks", "tiles", "brick"):
        plane = planar_coordinates(n)
        # (brick length, row height, mortar, second colour's shade, offset)
        shape = {"wood_planks": (6.0 * s, s, 0.0015, 0.8, 0.5),
                 "tiles": (s, s, 0.005, 0.93, 0.0),
                 "brick": (s, 0.3 * s, 0.01, 0.75, 0.5)}[p]
        mortar = rgba(m["accent_rgb"], 0.5) if p == "wood_planks" else accent
        bricks = n.add("ShaderNodeTexBrick", [
            ("Vector", plane), ("Color1", base), ("Color2", rgba(m["base_rgb"], shape[3])),
            ("Mortar", mortar), ("Scale", 1.0), ("Mortar Size", shape[2]),
            ("Mortar Smooth", 0.1), ("Bias", 0.0), ("Brick Width", shape[0]),
            ("Row Height", shape[1])], offset=shape[4], offset_frequency=2).outputs["Color"]
        if p == "wood_planks":
            # Grain along each plank: bands across a vector stretched along its length.
            along = n.add("ShaderNodeVectorMath", [(0, plane), (1, (0.15, 1.0, 1.0))],
                          operation="MULTIPLY").outputs["Vector"]
            grain = n.add("ShaderNodeTexWave", [("Vector", along), ("Scale", 0.5 / s),
                                                ("Distortion", 6.0), ("Detail", 3.0)],
                          wave_type="BANDS", bands_direction="Y").outputs["Fac"]
            return n.mix("RGBA", n.math("MULTIPLY", grain, 0.45), bricks, accent), 0.0
        spots = n.ramp(noise(n, world, 0.5 * s if p == "tiles" else 0.08), 0.3, 0.7)
        return n.mix("RGBA", n.math("MULTIPLY", spots, 0.25), bricks, rgba(m["base_rgb"], 0.8)), 0.0
    if p == "stone":
        plane = planar_coordinates(n)
        cells = n.add("ShaderNodeTexVoronoi", [("Vector", plane), ("Scale", 1.0 / s)])
        edges = n.add("ShaderNodeTexVoronoi", [("Vector", plane), ("Scale", 1.0 / s)],
                      feature="DISTANCE_TO_EDGE").outputs["Distance"]
        shade = n.mix("RGBA", n.math("MULTIPLY", n.grey(cells.outputs["Color"]), 0.8), base, accent)
        veined = n.mix("RGBA", n.math("MULTIPLY", noise(n, world, 0.3 * s, 6.0, 0.6), 0.3), shade, accent)
        return n.mix("RGBA", n.ramp(edges, 0.03, 0.0), veined, rgba(m["accent_rgb"], 0.55)), 0.0
    if p == "wallpaper":
        plane = planar_coordinates(n)
        stripes = n.add("ShaderNodeTexWave", [("Vector", plane), ("Scale", 0.5 / s)],
                        wave_type="BANDS", bands_direction="X").outputs["Fac"]
        dots = n.add("ShaderNodeTexVoronoi", [("Vector", plane), ("Scale", 2.0 / s),
                                              ("Randomness", 0.3)]).outputs["Distance"]
        motif = n.math("MAXIMUM", n.ramp(stripes, 0.45, 0.5), n.ramp(dots, 0.18, 0.12))
        return n.mix("RGBA", n.math("MULTIPLY", motif, 0.8), base, accent), 0.0
    if p == "carpet":
        fibres = noise(n, world, 0.004, 2.0)
        blotches = n.ramp(noise(n, world, s, 5.0, 0.6), 0.35, 0.65)
        both = n.math("MULTIPLY_ADD", blotches, 0.6, n.math("MULTIPLY", fibres, 0.4))
        return n.mix("RGBA", both, base, accent), 0.0
    if p in ("plaster", "paint", "plastic", "metal"):
        amount = {"plaster": 1.0, "paint": 0.6, "plastic": 0.3, "metal": 0.4}[p]
        detail = {"plaster": 8.0, "paint": 4.0, "plastic": 2.0, "metal": 4.0}[p]
        vector = world
        if p == "metal":  # brushed: the noise stretched along one axis
            vector = n.add("ShaderNodeVectorMath", [(0, world), (1, (20.0, 1.0, 1.0))],
                           operation="MULTIPLY").outputs["Vector"]
        f = n.ramp(noise(n, vector, s, detail, 0.6), 0.3, 0.7)
        return n.mix("RGBA", n.math("MULTIPLY", f, amount), base, accent), float(p == "metal")
    if p == "wood":
        rings = n.add("ShaderNodeTexWave", [("Vector", world), ("Scale", 1.0 / s),
                                            ("Distortion", 8.0), ("Detail", 4.0)],
                      wave_type="RINGS").outputs["Fac"]
        return n.mix("RGBA", n.math("MULTIPLY", rings, 0.7), base, accent), 0.0
    if p == "fabric":
        plane = planar_coordinates(n)
        warp = n.add("ShaderNodeTexWave", [("Vector", plane), ("Scale", 0.5 / s)],
                     wave_type="BANDS", bands_direction="X").outputs["Fac"]
        weft = n.add("ShaderNodeTexWave", [("Vector", plane), ("Scale", 0.5 / s)],
                     wave_type="BANDS", bands_direction="Y").outputs["Fac"]
        weave = n.math("MULTIPLY", warp, weft)
        folds = n.ramp(noise(n, world, 0.12, 4.0), 0.3, 0.7)
        woven = n.mix("RGBA", n.math("MULTIPLY", weave, 0.5), base, accent)
        return n.mix("RGBA", n.math("MULTIPLY", folds, 0.3), woven, rgba(m["base_rgb"], 0.7)), 0.0
    if p == "leather":
        grain = n.add("ShaderNodeTexVoronoi", [("Vector", world), ("Scale", 1.0 / s)]).outputs["Distance"]
        wear = n.ramp(noise(n, world, 0.1, 4.0), 0.3, 0.7)
        both = n.math("MULTIPLY_ADD", grain, 0.5, n.math("MULTIPLY", wear, 0.4))
        return n.mix("RGBA", both, accent, base), 0.0
    raise RuntimeError(f"materials: unknown pattern {p!r} for {m['object']!r}")


def drawn_material(m):
    """A Principled BSDF whose colour is the drawn pattern; no bump: the shading normal (and so
    the Normal pass) stays the geometry's."""
    mat = bpy.data.materials.new(f"egogen_{m['pattern']}_{m['object']}")
    mat.diffuse_color = rgba(m["base_rgb"])
    mat.use_nodes = True
    n = Nodes(mat)
    colour, metallic = pattern_colour(n, m)
    bsdf = n.nodes["Principled BSDF"]
    n.feed(bsdf.inputs["Base Color"], colour)
    bsdf.inputs["Roughness"].default_value = m["roughness"]
    bsdf.inputs["Metallic"].default_value = metallic
    return mat


def apply_materials(scene, materials):
    """Replaces the materials of each listed object with its drawn one (a mesh shared with an
    object not listed is copied first)."""
    by_name = {o.name: o for o in scene.objects if o.type == "MESH"}
    for m in materials:
        obj = by_name.get(blender_name(m["object"]))
        if obj is None:
            raise RuntimeError(f"materials: no mesh object {m['object']!r} in the scene")
        if obj.data.users > 1:
            obj.data = obj.data.copy()
        mat = drawn_material(m)
        obj.data.materials.clear()
        obj.data.materials.append(mat)
        obj.data.polygons.foreach_set("material_index", [0] * len(obj.data.polygons))
        for slot in obj.material_slots:
            slot.link = "DATA"


def blender_name(name):
    """The name Blender keeps for an object called `name`: at most 63 bytes of UTF-8."""
    return name.encode("utf-8")[:63].decode("utf-8", "ignore")


def check_object_names(scene, spec):
    """The segmentation contract: every scene object Rust gave an id (but those egogen adds:
    obstacles, held objects) is an object of the imported scene by the same name (as Blender keeps it), and no two names become one. An
    object Blender renamed would otherwise draw with id 0 or another's id: an error instead,
    naming the objects."""
    added = {o["name"] for key in ("obstacles", "held_objects") for o in spec.get(key, [])}
    kept = {}
    for name, _ in spec["object_ids"]:
        if name not in added:
            kept.setdefault(blender_name(name), []).append(name)
    merged = [names for names in kept.values() if len(names) > 1]
    if merged:
        raise RuntimeError(
            f"segmentation: object names that Blender keeps as one (cut at 63 bytes): {merged[:5]}"
        )
    present = {o.name for o in scene.objects}
    missing = [names[0] for b, names in kept.items() if b not in present]
    if missing:
        others = sorted(present - set(kept))[:5]
        raise RuntimeError(
            f"segmentation: {len(missing)} object(s) of the scene are not in Blender's import by "
            f"their name (first: {missing[:5]}); Blender's objects not in the ids: {others}"
        )


def build_scene(spec):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.edit.keyframe_new_interpolation_type = "LINEAR"
    import_scene_file(spec["scene_file"], spec["scene_up_axis"], spec.get("scene_unit_m", 1.0))
    if spec.get("scene_split"):
        split_scene(spec["scene_split"])
    scene = bpy.context.scene
    if spec.get("ceiling"):
        add_ceiling(scene, spec["ceiling"])
    # Blender cuts object names at 63 bytes of UTF-8: match the names as it keeps them.
    ids = {blender_name(name): i for name, i in spec["object_ids"]}
    check_object_names(scene, spec)
    for obj in scene.objects:
        obj.pass_index = ids.get(obj.name, 0)
    apply_materials(scene, spec.get("materials", []))
    bodies = [add_body(scene, b) for b in spec["bodies"]]
    # The bodies' parts and garments beside their ids (0 wherever no body material writes
    # them), registered before the first render: with persistent data, a pass added later is
    # not rendered. The colour raws carry them too, unread.
    parts = os.environ.get("EGOGEN_BLENDER_PART_AOV") != "0"
    for name, needed in ((PART_AOV, lambda b: parts and b.get("parts_npy")),
                         (GARMENT_AOV, lambda b: b.get("parts_npy") and b.get("outfit"))):
        if any(needed(b) for b in spec["bodies"]):
            aov = scene.view_layers[0].aovs.add()
            aov.name = name
            aov.type = "VALUE"
    # What moves besides the bodies and the camera, each with how it is keyed on a timeline
    # of a given frame step.
    movers = []
    for o in spec.get("obstacles", []):
        obj = add_obstacle(scene, o)
        movers.append(lambda step, obj=obj, o=o: key_obstacle(obj, o["keys"], step))
    for o in spec.get("held_objects", []):
        obj = add_held_object(scene, o)
        movers.append(lambda step, obj=obj, o=o: key_pose(obj, o["keys"], step))
    for o in spec.get("moved_objects", []):
        obj = scene.objects.get(blender_name(o["name"]))
        if obj is None:
            raise RuntimeError(f"moved_objects: no object {o['name']!r} in the imported scene")
        base = obj.matrix_world.copy()
        movers.append(lambda step, obj=obj, o=o, base=base: key_moved(obj, base, o["keys"], step))
    scene.render.fps = spec["fps"]
    scene.render.fps_base = spec["fps_base"]
    scene.render.engine = "CYCLES"
    # Keep Cycles' scene between the shard's renders: only what changes (the bodies, the
    # camera) is synced again, not the static scene's BVH or the world light's importance map
    # (with an HDRI that rebuild alone took 1.2 s of every render, docs/RENDERING.md).
    # EGOGEN_BLENDER_PERSISTENT_DATA=0 turns it off (for `cargo bench --bench render_cost`).
    scene.render.use_persistent_data = os.environ.get("EGOGEN_BLENDER_PERSISTENT_DATA") != "0"
    set_device(scene, spec.get("device", "cpu"))
    scene.world = bpy.data.worlds.new("egogen_world")
    scene.world.color = tuple(spec["lighting"]["world_rgb"])
    if spec["lighting"].get("world_hdri"):
        add_world_hdri(scene.world, spec["lighting"]["world_hdri"])
    for i, light in enumerate(spec["lighting"]["point_lights"]):
        data = bpy.data.lights.new(f"egogen_light_{i}", type="POINT")
        data.energy = light["watts"]
        data.shadow_soft_size = 0.2
        obj = bpy.data.objects.new(f"egogen_light_{i}", data)
        obj.location = light["position"]
        scene.collection.objects.link(obj)
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"  # set per render kind: set_rgb_mode, set_ground_truth_mode
    return scene, bodies, movers


def make_camera(scene, cam_spec):
    data = bpy.data.cameras.new(cam_spec["name"])
    lens = cam_spec["lens"]
    if "perspective" in lens:
        p = lens["perspective"]
        data.type = "PERSP"
        data.sensor_fit = "HORIZONTAL"
        data.sensor_width = p["sensor_width_mm"]
        data.lens = p["focal_mm"]
        data.shift_x = p["shift_x"]
        data.shift_y = p["shift_y"]
        scene.render.resolution_x = p["width_px"]
        scene.render.resolution_y = p["height_px"]
    elif "equidistant_fisheye" in lens:
        p = lens["equidistant_fisheye"]
        data.type = "PANO"
        data.panorama_type = "FISHEYE_EQUIDISTANT"
        data.fisheye_fov = p["fov_rad"]
        scene.render.resolution_x = p["size_px"]
        scene.render.resolution_y = p["size_px"]
    else:
        p = lens["polynomial_fisheye"]
        data.type = "PANO"
        data.panorama_type = "FISHEYE_LENS_POLYNOMIAL"
        data.sensor_fit = "HORIZONTAL"
        data.sensor_width = p["sensor_width_mm"]
        for i, k in enumerate(p["k"]):
            setattr(data, f"fisheye_polynomial_k{i}", k)
        data.shift_x = p["shift_x"]
        data.shift_y = p["shift_y"]
        # Cycles skips pixels whose θ exceeds half of it: the corners beyond the valid view.
        data.fisheye_fov = p["fov_rad"]
        scene.render.resolution_x = p["width_px"]
        scene.render.resolution_y = p["height_px"]
    scene.render.resolution_percentage = 100
    data.clip_start = cam_spec["clip_start_m"]
    data.clip_end = 1000.0
    cam = bpy.data.objects.new(cam_spec["name"], data)
    scene.collection.objects.link(cam)
    cam.rotation_mode = "QUATERNION"
    key_pose(cam, cam_spec["keys"])
    scene.camera = cam
    return cam


def set_frame_step(cam, cam_spec, bodies, movers, spec, frame_step):
    """Puts the camera, the bodies, the obstacles and the held objects on a timeline where one
    frame is `frame_step` frames of the motion: Cycles' motion vectors (to the frames before and
    after) then reach the previous and next saved frame."""
    key_pose(cam, cam_spec["keys"], frame_step)
    for obj, body in zip(bodies, spec["bodies"]):
        key_cache(obj, body["cache_keys"], frame_step)
    for rekey in movers:
        rekey(frame_step)


# What lights the colour render, put out while the shard renders ground truth.
_LIGHTS_OUT = {}


def lights_out(scene):
    """The ground truth renders unlit: every pass it keeps (depth, normal, position, object
    index, vector, the alpha of what was hit) is of the first hit's geometry, and lighting it
    was half of its path tracing (`tools/bench_ground_truth_lighting.py`). The world and the
    lamps are put back for the next colour render; doing so re-syncs the world's importance
    map once (about 1 s with an HDRI), once per camera of a shard."""
    if _LIGHTS_OUT:
        return
    _LIGHTS_OUT["world"] = scene.world
    _LIGHTS_OUT["lamps"] = [o for o in scene.objects if o.type == "LIGHT" and not o.hide_render]
    scene.world = None
    for obj in _LIGHTS_OUT["lamps"]:
        obj.hide_render = True


def lights_on(scene):
    if not _LIGHTS_OUT:
        return
    scene.world = _LIGHTS_OUT.pop("world")
    for obj in _LIGHTS_OUT.pop("lamps"):
        obj.hide_render = False


# Each object's non-camera ray visibility, switched off while a shard renders ground truth.
_RAYS_OFF = {}
_SECONDARY_RAYS = ("visible_diffuse", "visible_glossy", "visible_transmission",
                   "visible_volume_scatter", "visible_shadow")


def secondary_rays_off(scene):
    """The ground truth keeps only what camera rays see at their first hit (and through
    see-through surfaces, which camera rays still cross). Cycles still traces a bounce ray at the
    first hit with max_bounces = 0 and shades what it hits; with every object invisible to all
    but camera rays that ray hits nothing: 17 % less ground-truth path tracing at full Aria RGB
    size, every kept channel bit-identical (docs/RENDERING.md, "At full Aria size")."""
    if _RAYS_OFF:
        return
    for obj in scene.objects:
        _RAYS_OFF[obj.name] = tuple(getattr(obj, a) for a in _SECONDARY_RAYS)
        for a in _SECONDARY_RAYS:
            setattr(obj, a, False)


def secondary_rays_on(scene):
    for name, flags in _RAYS_OFF.items():
        obj = scene.objects.get(name)
        if obj is not None:
            for a, v in zip(_SECONDARY_RAYS, flags):
                setattr(obj, a, v)
    _RAYS_OFF.clear()


def set_rgb_mode(scene, rgb):
    lights_on(scene)
    secondary_rays_on(scene)
    # A shard's colour raws wait for its ground truth (all colour frames render first):
    # compressed, they take less of the disk meanwhile.
    scene.render.image_settings.exr_codec = "ZIP"
    layer = scene.view_layers[0]
    for p in ("z", "normal", "object_index", "vector", "position"):
        setattr(layer, "use_pass_" + p, False)
    scene.cycles.samples = rgb["samples"]
    scene.cycles.max_bounces = 12  # Blender's default (the ground truth sets 0)
    scene.cycles.use_adaptive_sampling = rgb["adaptive_threshold"] > 0
    if rgb["adaptive_threshold"] > 0:
        scene.cycles.adaptive_threshold = rgb["adaptive_threshold"]
    # `denoise`: the denoiser's prefilter ("accurate" or "fast"), or None for no denoiser.
    scene.cycles.use_denoising = rgb["denoise"] is not None
    if rgb["denoise"] is not None:
        scene.cycles.denoising_prefilter = rgb["denoise"].upper()
    scene.cycles.pixel_filter_type = "BLACKMAN_HARRIS"
    scene.cycles.filter_width = 1.5
    scene.cycles.seed = rgb["seed"]
    scene.render.film_transparent = False
    scene.render.use_motion_blur = rgb["shutter_frames"] > 0
    scene.render.motion_blur_shutter = max(rgb["shutter_frames"], 1e-3)
    scene.render.motion_blur_position = "CENTER"


def set_ground_truth_mode(scene, passes):
    lights_out(scene)
    secondary_rays_off(scene)
    # A ground-truth raw is read back and removed as soon as it is written (its frame's colour
    # is already there): uncompressed, Blender writes it in 0.17 s instead of 0.57 s at full
    # Aria RGB size and egogen reads it faster (docs/RENDERING.md, "At full Aria size"); both
    # codecs are lossless, so the frame files are the same bytes.
    scene.render.image_settings.exr_codec = "NONE"
    layer = scene.view_layers[0]
    for p in ("z", "normal", "object_index", "vector", "position"):
        setattr(layer, "use_pass_" + p, p in passes)
    scene.cycles.samples = 1
    # Every pass it keeps is of the first hit: no light paths beyond it.
    scene.cycles.max_bounces = 0
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    # One sample exactly at the pixel centre.
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 0.01
    scene.render.use_motion_blur = False
    # Alpha 1 where a surface was hit, 0 for background.
    scene.render.film_transparent = True


PARENT = os.getppid()


def timing(stage, seconds):
    print("EGOGEN_TIMING", stage, f"{seconds:.6f}", flush=True)


def write_frame(scene, frame, out, kind):
    """Renders one (sub)frame to `out`; `kind` (colour or ground_truth) names its timings."""
    if os.getppid() != PARENT:
        sys.exit("render_shard.py: the egogen supervisor is gone; stopping")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    partial = out + ".partial.exr"
    scene.render.filepath = partial
    whole = int(np.floor(frame))
    t0 = time.perf_counter()
    scene.frame_set(whole, subframe=frame - whole)
    t1 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    t2 = time.perf_counter()
    os.replace(partial, out)
    timing(kind + "_frame_update", t1 - t0)
    timing(kind + "_render", t2 - t1)
    print("EGOGEN_DONE", out, flush=True)


def probe_bodies(scene, bodies, probe):
    """Evaluated body vertices at (sub)frames, for checking the cache read-back."""
    result = []
    for t in probe["frames"]:
        whole = int(np.floor(t))
        scene.frame_set(whole, subframe=t - whole)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        per_body = []
        for obj in bodies:
            mesh = obj.evaluated_get(depsgraph).to_mesh()
            co = np.empty(3 * len(mesh.vertices), dtype=np.float64)
            mesh.vertices.foreach_get("co", co)
            per_body.append(co.tolist())
            obj.evaluated_get(depsgraph).to_mesh_clear()
        result.append({"frame": t, "vertices": per_body})
    with open(probe["output_json"], "w") as f:
        json.dump(result, f)


# Exit status of a failure that happens again on every try (the spec or the scene cannot be
# loaded): the supervisor does not retry it.
EXIT_SETUP_FAILED = 3


def set_up(spec):
    """Builds the spec's scene (exit EXIT_SETUP_FAILED, saying why, when it cannot)."""
    t0 = time.perf_counter()
    try:
        built = build_scene(spec)
    except Exception as e:  # noqa: BLE001 - any setup failure is reported the same way
        print(f"EGOGEN_SETUP_FAILED {type(e).__name__}: {e}", file=sys.stderr, flush=True)
        sys.exit(EXIT_SETUP_FAILED)
    timing("scene_import", time.perf_counter() - t0)
    return built


def render_cameras(spec, scene, bodies, movers):
    """Renders every frame of the spec's cameras in the scene built for it."""
    step = spec["ground_truth_frame_step"]
    for cam_spec in spec["cameras"]:
        t0 = time.perf_counter()
        cam = make_camera(scene, cam_spec)
        timing("camera_setup", time.perf_counter() - t0)
        if spec["rgb"] is not None:
            set_rgb_mode(scene, spec["rgb"])
            for frame in cam_spec["frames"]:
                write_frame(scene, frame["frame"], frame["rgb_exr"], "colour")
        if spec["ground_truth_passes"]:
            t0 = time.perf_counter()
            set_ground_truth_mode(scene, spec["ground_truth_passes"])
            if step != 1:
                set_frame_step(cam, cam_spec, bodies, movers, spec, step)
            timing("camera_setup", time.perf_counter() - t0)
            for frame in cam_spec["frames"]:
                write_frame(
                    scene, frame["frame"] / step, frame["ground_truth_exr"], "ground_truth")
            if step != 1:
                set_frame_step(cam, cam_spec, bodies, movers, spec, 1)
        # The next shard's camera is a new object: this one goes, with its keys.
        data = cam.data
        bpy.data.objects.remove(cam, do_unlink=True)
        bpy.data.cameras.remove(data)


def take_key(spec):
    """What a long-lived worker's scene is built from: the spec but its cameras (and probe)."""
    rest = {k: v for k, v in spec.items() if k not in ("cameras", "body_probe")}
    return json.dumps(rest, sort_keys=True)


def resident_mb():
    """This process's resident memory (MB), from /proc where there is one, else its peak."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6
    except (OSError, ValueError, IndexError):
        import resource
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        return peak / 1e6 if sys.platform == "darwin" else peak / 1e3


def serve(take_dir):
    """`render_shard.py --serve TAKE_DIR`: a long-lived worker for the take in TAKE_DIR (named on
    its command line so that a process list shows which take it renders). Reads one JSON
    object a line from standard input, `{"spec": SPEC.json, "log": LOG}`; renders each spec's
    shard in the scene built once, from the first spec (every later one must be of the same
    take), its standard error appended to LOG; prints `EGOGEN_SHARD_END <resident MB>` after
    each. Exits at the end of its input."""
    timing("ready", 0.0)
    built, key = None, None
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        errors = os.open(request["log"], os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        sys.stderr.flush()
        os.dup2(errors, 2)
        os.close(errors)
        with open(request["spec"]) as f:
            spec = json.load(f)
        if built is None:
            built, key = set_up(spec), take_key(spec)
        elif take_key(spec) != key:
            print(f"EGOGEN_SETUP_FAILED render_shard.py --serve {take_dir}: a shard of another "
                  "take; a long-lived worker renders one take", file=sys.stderr, flush=True)
            sys.exit(EXIT_SETUP_FAILED)
        render_cameras(spec, *built)
        print("EGOGEN_SHARD_END", f"{resident_mb():.1f}", flush=True)


def outfit_sheet(path):
    """`egogen body outfits`: each person of the spec, dressed as a take dresses them, front and
    back under one area light and a grey world, side by side in one PNG (two rows)."""
    with open(path) as f:
        spec = json.load(f)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = spec["samples"]
    scene.cycles.use_denoising = True
    h = spec["cell_px"]
    scene.render.resolution_x, scene.render.resolution_y = h // 2, h
    scene.render.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("sheet")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.35, 0.35, 0.35, 1.0)
    scene.world = world
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.data.lens = 85
    scene.collection.objects.link(cam)
    scene.camera = cam
    light = bpy.data.objects.new("light", bpy.data.lights.new("light", "AREA"))
    light.data.energy = 400
    light.data.size = 2.0
    scene.collection.objects.link(light)
    cells = []
    out_dir = os.path.dirname(spec["out"])
    for k, person in enumerate(spec["people"]):
        # The body frame is y up (z forward); Blender's z up (-y forward).
        verts = np.load(person["vertices_npy"])[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0])
        obj = body_object(person, verts)
        scene.collection.objects.link(obj)
        zmin, zmax = verts[:, 2].min(), verts[:, 2].max()
        middle = 0.5 * (zmin + zmax)
        for side, (name, sign) in enumerate((("front", -1.0), ("back", 1.0))):
            cam.location = (0.0, sign * 5.2, middle)
            cam.rotation_euler = (Vector((0.0, 0.0, middle)) - cam.location).to_track_quat("-Z", "Y").to_euler()
            light.location = (1.5, sign * 3.0, zmax + 1.0)
            light.rotation_euler = (Vector((0.0, 0.0, middle)) - light.location).to_track_quat("-Z", "Y").to_euler()
            scene.render.filepath = os.path.join(out_dir, f"cell_{k}_{name}.png")
            bpy.ops.render.render(write_still=True)
            cells.append((k, side, scene.render.filepath))
        bpy.data.objects.remove(obj)
    n = len(spec["people"])
    w = h // 2
    sheet = np.ones((2 * h, n * w, 4), dtype=np.float32)
    for k, side, cell in cells:
        image = bpy.data.images.load(cell)
        pixels = np.array(image.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1]
        sheet[side * h:(side + 1) * h, k * w:(k + 1) * w] = pixels
        bpy.data.images.remove(image)
    out = bpy.data.images.new("sheet", n * w, 2 * h, alpha=True)
    out.pixels.foreach_set(sheet[::-1].ravel())
    out.filepath_raw = spec["out"]
    out.file_format = "PNG"
    out.save()


def main():
    args = script_args()
    if args[:1] == ["--check-device"] and len(args) == 2:
        check_device(args[1])
        return
    if args[:1] == ["--outfit-sheet"] and len(args) == 2:
        outfit_sheet(args[1])
        return
    if args[:1] == ["--serve"] and len(args) == 2:
        serve(args[1])
        return
    timing("ready", 0.0)
    spec = load_spec()
    scene, bodies, movers = set_up(spec)
    if spec.get("body_probe"):
        probe_bodies(scene, bodies, spec["body_probe"])
    render_cameras(spec, scene, bodies, movers)


if __name__ == "__main__":
    main()
