"""cycles_render.py -- renders a glTF scene with Blender's Cycles, an independent path tracer to
compare `iird render --method pt` with (outside `make test`; Debian's blender package, 3.4).

    blender -b --factory-startup --python tools/cycles_render.py -- SCENE.gltf OUT.exr \
        [--size 320x240] [--samples 256] [--bounces 1]

The glTF is imported by Blender's own importer (KHR_lights_punctual read back to watts as
Blender writes them, materials as Principled BSDF nodes with their textures), its camera made the
scene camera, and the frame rendered with Cycles on the CPU into a linear 32-bit EXR (view
transform "Standard", no film filter beyond Cycles' default, no denoising). --bounces is Cycles'
max_bounces: the number of bounces *after* the first hit, so it matches `iird --bounces B+1`.
CC0, part of iir.
"""
import argparse
import sys

import numpy as np

# Blender 3.4's glTF importer still uses np.bool, which Debian's numpy no longer has.
if not hasattr(np, "bool"):
    np.bool = bool

import bpy  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="cycles_render.py")
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--size", default="320x240")
    p.add_argument("--samples", type=int, default=256)
    p.add_argument("--bounces", type=int, default=1)
    p.add_argument("--only-light", default="",
                   help="delete every light but this one (by its glTF name)")
    p.add_argument("--lambert", action="store_true",
                   help="replace every opaque, non-emissive Principled BSDF by a Diffuse BSDF of "
                        "its base colour (texture and normal map kept): a diagnostic that leaves "
                        "out the two renderers' BSDF models (iir: a sidecar giving those "
                        "materials \"kind\": \"diffuse\")")
    return p.parse_args(argv)


def make_lambert(mat):
    """The material's Principled BSDF replaced by a Diffuse BSDF (roughness 0: Lambert) of the
    same base colour and normal; materials with alpha or emission are left as they are."""
    if not mat.use_nodes:
        return
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    for pr in [n for n in nodes if n.type == "BSDF_PRINCIPLED"]:
        emissive = pr.inputs["Emission"].is_linked or pr.inputs["Emission Strength"].default_value * \
            max(pr.inputs["Emission"].default_value[:3]) > 0
        if pr.inputs["Alpha"].is_linked or emissive:
            continue
        d = nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Roughness"].default_value = 0.0
        for name in ("Color", "Normal"):
            src = pr.inputs["Base Color" if name == "Color" else "Normal"]
            if src.is_linked:
                links.new(src.links[0].from_socket, d.inputs[name])
            elif name == "Color":
                d.inputs["Color"].default_value = src.default_value
        for link in list(pr.outputs["BSDF"].links):
            links.new(d.outputs["BSDF"], link.to_socket)


def clear():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def setup_render(args):
    sc = bpy.context.scene
    w, h = (int(v) for v in args.size.split("x"))
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = args.samples
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.max_bounces = args.bounces
    for kind in ("diffuse", "glossy", "transmission", "volume", "transparent"):
        setattr(sc.cycles, kind + "_bounces", max(args.bounces, 8 if kind == "transparent" else 0))
    sc.cycles.sample_clamp_direct = 0.0
    sc.cycles.sample_clamp_indirect = 0.0
    sc.cycles.caustics_reflective = True
    sc.cycles.caustics_refractive = True
    sc.cycles.seed = 1
    sc.render.resolution_x, sc.render.resolution_y = w, h
    sc.render.resolution_percentage = 100
    sc.render.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.view_settings.exposure = 0.0
    sc.view_settings.gamma = 1.0
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
    sc.render.image_settings.color_mode = "RGB"
    # no world light: the scene's lights only, as iir renders it
    if sc.world is None:
        sc.world = bpy.data.worlds.new("black")
    sc.world.use_nodes = True
    bg = sc.world.node_tree.nodes.get("Background")
    if bg:
        bg.inputs[1].default_value = 0.0


def main():
    args = parse_args()
    clear()
    bpy.ops.import_scene.gltf(filepath=args.scene)
    cams = [o for o in bpy.context.scene.objects if o.type == "CAMERA"]
    if not cams:
        sys.exit("cycles_render.py: the scene has no camera")
    bpy.context.scene.camera = cams[0]
    # the point, spot and sun lights as points (no soft radius): iir's are ideal
    for o in bpy.context.scene.objects:
        if o.type == "LIGHT" and o.data.type in ("POINT", "SPOT"):
            o.data.shadow_soft_size = 0.0
        if o.type == "LIGHT" and o.data.type == "SUN":
            o.data.angle = 0.0
    if args.only_light:
        for o in list(bpy.context.scene.objects):
            if o.type == "LIGHT" and o.data.name != args.only_light and o.name != args.only_light:
                bpy.data.objects.remove(o, do_unlink=True)
    if args.lambert:
        for mat in bpy.data.materials:
            make_lambert(mat)
    setup_render(args)
    bpy.context.scene.render.filepath = args.out
    bpy.ops.render.render(write_still=True)
    print("cycles_render.py: wrote", args.out)


main()
