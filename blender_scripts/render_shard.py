"""Render one shard: build the scene from files Rust wrote, render every frame, save EXRs.

Run by egogen (`python render_shard.py SPEC.json` with PyPI bpy, or
`blender --background --python-exit-code 1 --python render_shard.py -- SPEC.json`).
Thin on purpose: every number comes from the spec (see src/render/protocol.rs). Each frame is
written to `<output>.partial.exr` and renamed, so a killed worker never leaves a half-written
file under the final name. Prints one `EGOGEN_DONE <path>` line per finished frame.
"""
import json
import os
import sys

import bpy


def load_spec():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    if len(args) != 1:
        sys.exit("usage: render_shard.py SPEC.json")
    with open(args[0]) as f:
        return json.load(f)


def build_scene(spec):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=spec["scene_glb"])
    ids = dict(spec["object_ids"])
    for obj in bpy.context.scene.objects:
        obj.pass_index = ids.get(obj.name, 0)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = spec["samples"]
    scene.cycles.use_denoising = False
    scene.world = bpy.data.worlds.new("egogen_world")
    scene.world.color = (0.05, 0.05, 0.05)
    sun = bpy.data.objects.new("egogen_sun", bpy.data.lights.new("egogen_sun", type="SUN"))
    scene.collection.objects.link(sun)
    layer = scene.view_layers[0]
    layer.use_pass_z = True
    layer.use_pass_normal = True
    layer.use_pass_object_index = True
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    return scene


def render_camera(scene, cam_spec):
    data = bpy.data.cameras.new(cam_spec["name"])
    data.sensor_fit = "HORIZONTAL"
    data.sensor_width = cam_spec["sensor_width_mm"]
    data.lens = cam_spec["focal_mm"]
    data.shift_x = cam_spec["shift_x"]
    data.shift_y = cam_spec["shift_y"]
    data.clip_start = 0.01
    data.clip_end = 1000.0
    cam = bpy.data.objects.new(cam_spec["name"], data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    scene.render.resolution_x = cam_spec["width_px"]
    scene.render.resolution_y = cam_spec["height_px"]
    scene.render.resolution_percentage = 100
    from mathutils import Matrix
    for frame in cam_spec["frames"]:
        cam.matrix_world = Matrix(frame["matrix_world"])
        out = frame["output_exr"]
        os.makedirs(os.path.dirname(out), exist_ok=True)
        partial = out + ".partial.exr"
        scene.render.filepath = partial
        scene.frame_set(frame["frame"])
        bpy.ops.render.render(write_still=True)
        os.replace(partial, out)
        print("EGOGEN_DONE", out, flush=True)


def main():
    spec = load_spec()
    scene = build_scene(spec)
    for cam_spec in spec["cameras"]:
        render_camera(scene, cam_spec)


main()
