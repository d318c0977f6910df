"""What lighting costs the ground-truth render, and what turning it off per render costs back.

The ground-truth render (`blender_scripts/render_shard.py`, `set_ground_truth_mode`: 1 sample,
no bounces, the depth, normal, position, object-index and vector passes) kept the scene's
lamp and HDRI world until 2026-11-28, so its one sample lit the first hit; a shard now puts
them out once before its ground-truth renders (`lights_out`). This renders the shipped
apartment under an HDRI shipped in Blender and a 300 W lamp, as the ground truth is rendered
(Cycles, CPU, persistent data), and times each render call:

- lit: the lights as they are, nothing changed between renders (the ground truth until
  2026-11-28);
- unlit: no world and the lamp hidden, nothing changed between renders (as a shard renders
  its ground truth now, having put the lights out once with `render_shard.lights_out`);
- lit / unlit in turn: what a shard would do to light the colour render and not the ground
  truth (every change re-syncs the world's importance map);
- ray visibility off / on in turn: the same by the lights' ray visibility instead;
- lit without the combined pass.

    ~/.cache/egogen/bpy-4.5/bin/python tools/bench_ground_truth_lighting.py [SIZE]

SIZE: the square image's side in pixels (default 704: the Aria RGB camera at half size).
"""

import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender_scripts"))
import render_shard  # noqa: E402 - the shard script's own ground-truth settings and lights

GROUND_TRUTH_PASSES = ["z", "normal", "object_index", "vector", "position"]
SIZE = int(sys.argv[1]) if len(sys.argv) > 1 else 704
REPEATS = 3


def world_hdri():
    # The HDRIs shipped with Blender (CC0, Poly Haven), found as render_shard.py finds them.
    folder = bpy.utils.system_resource("DATAFILES", path="studiolights/world")
    if not folder or not os.path.isdir(folder):
        sys.exit(f"bench_ground_truth_lighting.py: no HDRI folder at {folder}")
    return os.path.join(folder, sorted(f for f in os.listdir(folder) if f.endswith(".exr"))[0])


def build():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(ROOT, "assets", "scenes", "apartment.glb"))
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.use_persistent_data = True
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = (0.5, 0.0, 1.6)
    cam.rotation_euler = (1.5, 0.0, 0.6)
    world = bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    env = world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(world_hdri())
    background = world.node_tree.nodes["Background"]
    world.node_tree.links.new(env.outputs[0], background.inputs[0])
    lamp = bpy.data.objects.new("lamp", bpy.data.lights.new("lamp", "POINT"))
    lamp.data.energy = 300.0
    lamp.location = (0.0, 0.0, 2.4)
    scene.collection.objects.link(lamp)
    # The ground truth's settings, from the shard script itself, then lit again to start.
    render_shard.set_ground_truth_mode(scene, GROUND_TRUTH_PASSES)
    render_shard.lights_on(scene)
    layer = scene.view_layers[0]
    return scene, world, lamp, layer


def render():
    t = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    return time.perf_counter() - t


def lights(scene, on):
    """As a shard does: the world and the lamps out for the ground truth, back for colour."""
    if on:
        render_shard.lights_on(scene)
    else:
        render_shard.lights_out(scene)


def visibility(world, lamp, on):
    for key in ("diffuse", "glossy", "transmission", "scatter"):
        setattr(world.cycles_visibility, key, on)
    for key in ("diffuse", "glossy", "transmission", "volume_scatter"):
        setattr(lamp, "visible_" + key, on)


def main():
    scene, world, lamp, layer = build()
    rows = []
    render()  # the first render syncs the whole scene
    rows.append(("lit (the ground truth until 2026-11-28)", [render() for _ in range(REPEATS)]))
    lights(scene, False)
    render()
    rows.append(
        ("unlit: no world, lamp hidden (the ground truth now)", [render() for _ in range(REPEATS)])
    )
    lit, unlit = [], []
    for _ in range(REPEATS):
        lights(scene, True)
        lit.append(render())
        lights(scene, False)
        unlit.append(render())
    rows.append(("lit, in turn with unlit", lit))
    rows.append(("unlit, in turn with lit", unlit))
    lights(scene, True)
    render()
    on, off = [], []
    for _ in range(REPEATS):
        visibility(world, lamp, False)
        off.append(render())
        visibility(world, lamp, True)
        on.append(render())
    rows.append(("ray visibility off, in turn", off))
    rows.append(("ray visibility on, in turn", on))
    layer.use_pass_combined = False
    render()
    rows.append(("lit, no combined pass", [render() for _ in range(REPEATS)]))
    print(f"\n| ground-truth render, {SIZE}×{SIZE}, 1 sample | s per render (median of {REPEATS}) |")
    print("|---|---|")
    for name, seconds in rows:
        print(f"| {name} | {sorted(seconds)[len(seconds) // 2]:.2f} |")


main()
