"""Renders a scene exported by sss-peers (scene.json and OBJ meshes) with Blender Cycles.

Usage: python cycles_render.py SCENE.json OUT_PREFIX --spp N --seed S --threads T
       [--batches K] --mode volume|random-walk|random-walk-skin|burley

Needs the `bpy` module (`pip install "bpy==4.5.*"` on Python 3.11). Renders K independent
images (seeds S, S + 1, ...) of N samples per pixel each and writes OUT_PREFIX.f32 (K x height
x width x 3 little-endian float32, rows from the top, linear RGB, box-filtered pixels) and
OUT_PREFIX.json ({"seconds": the renders' seconds, "width", "height", "batches"}), like
mitsuba_render.py.

How the scene is built (docs/peers.md says how each choice was checked):
- every setting that would change the light transport is set: no denoiser, no clamping, no
  adaptive sampling, caustics on (light that refracts into a medium and out again is a
  caustic path to Cycles), 1024 bounces of every kind, a 1-pixel box filter, the Standard view
  transform and linear output;
- the OBJ's coordinates are kept as they are (Blender's own axes: up Z, forward Y), with its
  vertex normals as custom normals;
- the camera looks down its local -Z with +Y up, the vertical field of view given
  (sensor fit vertical);
- a quad light is an area light whose power makes the exported radiance, L = P / (pi A), and
  an environment light is the world's colour; neither is seen in glossy reflections, so the
  light the boundaries reflect towards the camera is left out as sss leaves it out;
- `--mode volume`: a smooth Glass BSDF at eta around Volume Absorption + Volume Scatter with
  the exported sigma_a, sigma_s and g (the same physics as Mitsuba's and volpath's);
- `--mode random-walk`, `random-walk-skin`, `burley`: the Principled BSDF's subsurface at
  Cycles' own parameters, inverted from the medium: Cycles sets sigma_t = 1 / (d (1 - g)) for a
  radius d (radius x scale) and the single-scattering albedo from the base colour through its
  fit alpha(A, g) (kernel/integrator/subsurface_random_walk.h), so d = 1 / (sigma_t (1 - g))
  and A solves alpha(A, g) = sigma_s / sigma_t by bisection. Below alpha 0.2 Cycles raises
  alpha to 0.2 and scales its weight: such a channel is not the medium asked for.
"""

import argparse
import json
import math
import os
import sys
import tempfile
import time

import numpy as np


def cycles_alpha(albedo, g):
    """Cycles' single-scattering albedo for a surface albedo (subsurface_random_walk_remap)."""
    g2, g3, g4, g5, g6, g7 = g * g, g**3, g**4, g**5, g**6, g**7
    a = (1.8260523782 - 1.28451056436 * g - 1.79904629312 * g2 + 9.19393289202 * g3
         - 22.8215585862 * g4 + 32.0234874259 * g5 - 23.6264803333 * g6 + 7.21067002658 * g7)
    b = 4.98511194385 + 0.127355959438 * math.exp(
        31.1491581433 * g - 201.847017512 * g2 + 841.576016723 * g3 - 2018.09288505 * g4
        + 2731.71560286 * g5 - 1935.41424244 * g6 + 559.009054474 * g7)
    c = (1.09686102424 - 0.394704063468 * g + 1.05258115941 * g2 - 8.83963712726 * g3
         + 28.8643230661 * g4 - 46.8802913581 * g5 + 38.5402837518 * g6 - 12.7181042538 * g7)
    d = (0.496310210422 + 0.360146581622 * g - 2.15139309747 * g2 + 17.8896899217 * g3
         - 55.2984010333 * g4 + 82.065982243 * g5 - 58.5106008578 * g6 + 15.8478295021 * g7)
    e = 4.23190299701 + 0.00310603949088 * math.exp(
        76.7316253952 * g - 594.356773233 * g2 + 2448.8834203 * g3 - 5576.68528998 * g4
        + 7116.60171912 * g5 - 4763.54467887 * g6 + 1303.5318055 * g7)
    f = (2.40602999408 - 2.51814844609 * g + 9.18494908356 * g2 - 79.2191708682 * g3
         + 259.082868209 * g4 - 403.613804597 * g5 + 302.85712436 * g6 - 87.4370473567 * g7)
    blend = albedo**0.25
    alpha = (1.0 - blend) * a * math.atan(b * albedo) ** c + blend * d * math.atan(e * albedo) ** f
    return min(max(alpha, 0.0), 0.999999)


def invert_alpha(alpha, g):
    """The base colour A in [0, 1] with cycles_alpha(A, g) = alpha (bisection; it increases)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if cycles_alpha(mid, g) < alpha:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, required=True)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--batches", type=int, default=1)
    ap.add_argument("--mode", choices=["volume", "random-walk", "random-walk-skin", "burley"],
                    required=True)
    args = ap.parse_args()

    import bpy

    base = os.path.dirname(os.path.abspath(args.scene))
    with open(args.scene) as f:
        desc = json.load(f)
    build(bpy, desc, base, args)
    scene = bpy.context.scene
    w, h = scene.render.resolution_x, scene.render.resolution_y
    images = []
    seconds = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.batches):
            scene.cycles.seed = args.seed + k
            path = os.path.join(tmp, f"batch{k}.exr")
            scene.render.filepath = path
            t0 = time.perf_counter()
            bpy.ops.render.render(write_still=True)
            seconds += time.perf_counter() - t0
            img = bpy.data.images.load(path)
            px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[:, :, :3]
            bpy.data.images.remove(img)
            # Blender's rows run from the bottom.
            images.append(px[::-1])
    arr = np.ascontiguousarray(np.stack(images).astype("<f4"))
    arr.tofile(args.out + ".f32")
    with open(args.out + ".json", "w") as f:
        json.dump({"seconds": seconds, "width": w, "height": h, "batches": arr.shape[0]}, f)


def look_at(position, target, up):
    """The world matrix of an object at `position` whose local -Z looks at `target`, +Y up."""
    p, t, u = (np.array(v, dtype=float) for v in (position, target, up))
    f = t - p
    f /= np.linalg.norm(f)
    r = np.cross(f, u)
    r /= np.linalg.norm(r)
    y = np.cross(r, f)
    m = np.identity(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, y, -f, p
    return m


def build(bpy, desc, base, args):
    from mathutils import Matrix

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cyc = scene.cycles
    cyc.device = "CPU"
    cyc.samples = args.spp
    cyc.use_adaptive_sampling = False
    cyc.use_denoising = False
    cyc.sample_clamp_direct = 0.0
    cyc.sample_clamp_indirect = 0.0
    cyc.caustics_reflective = True
    cyc.caustics_refractive = True
    cyc.blur_glossy = 0.0
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "volume_bounces", "transparent_max_bounces"):
        setattr(cyc, k, 1024)
    cyc.pixel_filter_type = "BOX"
    cyc.filter_width = 1.0
    if args.threads > 0:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = args.threads
    cam = desc["camera"]
    scene.render.resolution_x = cam["width"]
    scene.render.resolution_y = cam["height"]
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.color_mode = "RGBA"

    cdata = bpy.data.cameras.new("camera")
    cdata.sensor_fit = "VERTICAL"
    cdata.angle_y = math.radians(cam["vfov_deg"])
    cdata.clip_start = 1e-4
    cdata.clip_end = 1e8
    cobj = bpy.data.objects.new("camera", cdata)
    cobj.matrix_world = Matrix(look_at(cam["position"], cam["target"], cam["up"]).tolist())
    scene.collection.objects.link(cobj)
    scene.camera = cobj

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    scene.world = world
    for i, light in enumerate(desc["lights"]):
        if light["type"] == "quad":
            c = np.array(light["corner"], dtype=float)
            u = np.array(light["edge_u"], dtype=float)
            v = np.array(light["edge_v"], dtype=float)
            n = np.cross(u, v)
            area = np.linalg.norm(n)
            n /= area
            ldata = bpy.data.lights.new(f"light{i}", type="AREA")
            ldata.shape = "RECTANGLE"
            ldata.size = float(np.linalg.norm(u))
            ldata.size_y = float(np.linalg.norm(v))
            # Power for radiance L of a one-sided Lambertian emitter: P = L pi A (per channel,
            # as colour times energy).
            rad = np.array(light["radiance"], dtype=float)
            peak = float(rad.max()) if rad.max() > 0 else 1.0
            ldata.color = tuple(rad / peak)
            ldata.energy = peak * math.pi * area
            lobj = bpy.data.objects.new(f"light{i}", ldata)
            # Local X along edge_u, Y against edge_v, so that local -Z is edge_u x edge_v.
            m = np.identity(4)
            m[:3, 0] = u / np.linalg.norm(u)
            m[:3, 1] = -v / np.linalg.norm(v)
            m[:3, 2] = -n
            m[:3, 3] = c + 0.5 * u + 0.5 * v
            lobj.matrix_world = Matrix(m.tolist())
            lobj.visible_glossy = False
            scene.collection.objects.link(lobj)
        elif light["type"] == "environment":
            r = light["radiance"]
            bg.inputs["Color"].default_value = (r[0], r[1], r[2], 1.0)
        elif light["type"] == "sun":
            # Cycles' sun: strength is the irradiance on a surface facing it (W/m^2), angle
            # its angular diameter (radians); it shines along its local -Z.
            e = np.array(light["irradiance"], dtype=float)
            peak = float(e.max()) if e.max() > 0 else 1.0
            ldata = bpy.data.lights.new(f"light{i}", type="SUN")
            ldata.color = tuple(e / peak)
            ldata.energy = peak
            ldata.angle = float(light["angular_diameter"])
            lobj = bpy.data.objects.new(f"light{i}", ldata)
            d = np.array(light["direction"], dtype=float)
            z = -d / np.linalg.norm(d)
            x = np.cross([0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0], z)
            x /= np.linalg.norm(x)
            m = np.identity(4)
            m[:3, 0], m[:3, 1], m[:3, 2] = x, np.cross(z, x), z
            lobj.matrix_world = Matrix(m.tolist())
            lobj.visible_glossy = False
            scene.collection.objects.link(lobj)
        else:
            sys.exit(f"error: {args.scene}: light {i} is a {light['type']} light, which the "
                     "exported peers do not take")
    world.cycles_visibility.glossy = False

    for i, obj in enumerate(desc["objects"]):
        before = set(bpy.data.objects)
        bpy.ops.wm.obj_import(filepath=os.path.join(base, obj["mesh"]),
                              forward_axis="Y", up_axis="Z")
        new = [o for o in bpy.data.objects if o not in before]
        mat = bpy.data.materials.new(f"material{i}")
        mat.use_nodes = True
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        for node in list(nodes):
            nodes.remove(node)
        out = nodes.new("ShaderNodeOutputMaterial")
        m = obj["material"]
        if m["type"] == "medium":
            sa = np.array(m["sigma_a"], dtype=float)
            ss = np.array(m["sigma_s"], dtype=float)
            g, eta = float(m["g"]), float(m["eta"])
            if args.mode == "volume":
                glass = nodes.new("ShaderNodeBsdfGlass")
                # GGX at roughness 0 is Cycles' smooth glass (4.x has no "sharp" option).
                glass.distribution = "GGX"
                glass.inputs["Roughness"].default_value = 0.0
                glass.inputs["IOR"].default_value = eta
                glass.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
                links.new(glass.outputs[0], out.inputs["Surface"])
                absorb = nodes.new("ShaderNodeVolumeAbsorption")
                scatter = nodes.new("ShaderNodeVolumeScatter")
                # Cycles: sigma_a = density x (1 - colour), sigma_s = density x colour.
                da, ds = float(sa.max()), float(ss.max())
                absorb.inputs["Density"].default_value = da
                absorb.inputs["Color"].default_value = (*(1.0 - sa / da if da > 0 else np.ones(3)), 1.0)
                scatter.inputs["Density"].default_value = ds
                scatter.inputs["Color"].default_value = (*(ss / ds if ds > 0 else np.zeros(3)), 1.0)
                scatter.inputs["Anisotropy"].default_value = g
                add = nodes.new("ShaderNodeAddShader")
                links.new(absorb.outputs[0], add.inputs[0])
                links.new(scatter.outputs[0], add.inputs[1])
                links.new(add.outputs[0], out.inputs["Volume"])
            else:
                if not 0.0 <= g <= 0.9:
                    sys.exit(f"error: {args.scene}: object {i} has g = {g}, outside the range "
                             "[0, 0.9] of Cycles' subsurface albedo fit")
                st = sa + ss
                radius = 1.0 / (st * (1.0 - g))
                colour = [invert_alpha(a, g) for a in ss / st]
                p = nodes.new("ShaderNodeBsdfPrincipled")
                p.subsurface_method = {"random-walk": "RANDOM_WALK",
                                       "random-walk-skin": "RANDOM_WALK_SKIN",
                                       "burley": "BURLEY"}[args.mode]
                p.inputs["Base Color"].default_value = (*colour, 1.0)
                p.inputs["Subsurface Weight"].default_value = 1.0
                p.inputs["Subsurface Radius"].default_value = tuple(radius)
                p.inputs["Subsurface Scale"].default_value = 1.0
                p.inputs["Roughness"].default_value = 0.0
                p.inputs["IOR"].default_value = eta
                if "Subsurface IOR" in p.inputs:
                    p.inputs["Subsurface IOR"].default_value = eta
                if "Subsurface Anisotropy" in p.inputs:
                    p.inputs["Subsurface Anisotropy"].default_value = g
                links.new(p.outputs[0], out.inputs["Surface"])
        else:
            d = nodes.new("ShaderNodeBsdfDiffuse")
            d.inputs["Color"].default_value = (*m["albedo"], 1.0)
            links.new(d.outputs[0], out.inputs["Surface"])
        for o in new:
            if o.type == "MESH":
                o.data.materials.clear()
                o.data.materials.append(mat)
                for poly in o.data.polygons:
                    poly.use_smooth = True


if __name__ == "__main__":
    main()
