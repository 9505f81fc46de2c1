"""Renders a scene exported by sss-peers (scene.json and OBJ meshes) with Mitsuba 3.

Usage: python mitsuba_render.py SCENE.json OUT_PREFIX --spp N --seed S --threads T
       [--batches K] [--mode full|subsurface] [--integrator auto|NAME] [--rr-depth D]

Renders K independent images (seeds S, S + 1, ...) of N samples per pixel each and writes
OUT_PREFIX.f32 (K x height x width x 3 little-endian float32, rows from the top, linear RGB,
box-filtered pixels) and OUT_PREFIX.json ({"seconds": the full renders' seconds, "width",
"height", "batches"}).

The scene is built as the sss renderer sees it (the conventions are in docs/peers.md):
- translucent objects: a smooth `dielectric` boundary (int_ior = eta, ext_ior = 1) around a
  `homogeneous` medium with sigma_t = sigma_a + sigma_s and albedo sigma_s / sigma_t per
  channel (Mitsuba refuses RGB values above 1, so the colour is sigma_t / max and `scale` the
  max), isotropic or Henyey-Greenstein phase;
- `--mode subsurface` also renders each batch with every medium replaced by an opaque black
  one (albedo 0, a huge sigma_t), which holds only the light the boundaries reflect, and
  writes the difference: the light that crossed them (the subsurface term of sss);
- quad lights: one-sided `rectangle` area emitters with a `null` BSDF: like sss's quads they
  emit but block nothing (a ray goes on through them, to the environment say); environment
  lights: a `constant` emitter; diffuse objects: `diffuse` with their albedo;
- a pinhole `perspective` camera with fov_axis = "y" and a `box` pixel filter;
- the integrator (`--integrator auto`): `volpathmis` when some object holds a medium, else
  `path`. Mitsuba 3.9's `volpathmis` over-counts the environment seen through a `null`
  surface from a diffuse vertex (emitter sampling and BSDF sampling disagree on the MIS
  weight there): a grey Lambertian sphere under a constant environment with a null quad
  above came out 7 % too bright with it, right with `path` and `volpath`.
"""

import argparse
import json
import os
import sys
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, required=True)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--batches", type=int, default=1)
    ap.add_argument("--mode", choices=["full", "subsurface"], default="full")
    ap.add_argument("--integrator", default="auto")
    ap.add_argument("--rr-depth", type=int, default=5)
    args = ap.parse_args()

    import drjit as dr
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    if args.threads > 0:
        dr.set_thread_count(args.threads)

    base = os.path.dirname(os.path.abspath(args.scene))
    with open(args.scene) as f:
        desc = json.load(f)
    full = mi.load_dict(build(desc, base, args, opaque=False))
    black = mi.load_dict(build(desc, base, args, opaque=True)) if args.mode == "subsurface" else None
    images = []
    seconds = 0.0
    for b in range(args.batches):
        seed = args.seed + b
        t0 = time.perf_counter()
        img = np.asarray(mi.render(full, spp=args.spp, seed=seed), dtype=np.float64)[:, :, :3]
        seconds += time.perf_counter() - t0
        if black is not None:
            img = img - np.asarray(mi.render(black, spp=args.spp, seed=seed), dtype=np.float64)[:, :, :3]
        images.append(img)
    arr = np.ascontiguousarray(np.stack(images).astype("<f4"))
    arr.tofile(args.out + ".f32")
    with open(args.out + ".json", "w") as f:
        json.dump({"seconds": seconds, "width": arr.shape[2], "height": arr.shape[1],
                   "batches": arr.shape[0]}, f)


def build(desc, base, args, opaque):
    """The Mitsuba scene dictionary of `desc`; `opaque` makes every medium opaque black."""
    from mitsuba import ScalarTransform4f as T
    cam = desc["camera"]
    integrator = args.integrator
    if integrator == "auto":
        media = any(o["material"]["type"] == "medium" for o in desc["objects"])
        integrator = "volpathmis" if media else "path"
    scene = {
        "type": "scene",
        "integrator": {"type": integrator, "max_depth": -1, "rr_depth": args.rr_depth},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": cam["vfov_deg"],
            "to_world": T().look_at(
                origin=cam["position"], target=cam["target"], up=cam["up"]
            ),
            "sampler": {"type": "independent", "sample_count": args.spp},
            "film": {
                "type": "hdrfilm",
                "width": cam["width"],
                "height": cam["height"],
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
        },
    }
    for i, light in enumerate(desc["lights"]):
        if light["type"] == "quad":
            c = np.array(light["corner"], dtype=float)
            u = np.array(light["edge_u"], dtype=float)
            v = np.array(light["edge_v"], dtype=float)
            n = np.cross(u, v)
            n = n / np.linalg.norm(n)
            centre = c + 0.5 * u + 0.5 * v
            # The rectangle spans [-1, 1]^2 in z = 0 and emits towards +z: map x to u/2, y to
            # v/2 and z to the unit normal (det > 0, so +z goes to u x v).
            m = np.identity(4)
            m[:3, 0] = 0.5 * u
            m[:3, 1] = 0.5 * v
            m[:3, 2] = n
            m[:3, 3] = centre
            scene[f"light_{i}"] = {
                "type": "rectangle",
                "to_world": T(m.tolist()),
                "bsdf": {"type": "null"},
                "emitter": {
                    "type": "area",
                    "radiance": {"type": "rgb", "value": light["radiance"]},
                },
            }
        elif light["type"] == "environment":
            scene[f"light_{i}"] = {
                "type": "constant",
                "radiance": {"type": "rgb", "value": light["radiance"]},
            }
        elif light["type"] == "sun":
            sys.exit(f"error: {args.scene}: light {i} is a sun (a disc of finite angular "
                     "diameter), which Mitsuba 3 has no emitter for (its `directional` is a "
                     "delta light); render it with Cycles")
        else:
            sys.exit(f"error: {args.scene}: light {i} is a {light['type']} light, which a "
                     "path tracer cannot reach through a smooth dielectric")
    for i, obj in enumerate(desc["objects"]):
        shape = {
            "type": "obj",
            "filename": os.path.join(base, obj["mesh"]),
            "face_normals": False,
        }
        mat = obj["material"]
        if mat["type"] == "medium":
            sa = np.array(mat["sigma_a"], dtype=float)
            ss = np.array(mat["sigma_s"], dtype=float)
            st = sa + ss
            albedo = ss / st
            if opaque:
                st = np.full(3, 1e6)
                albedo = np.zeros(3)
            scale = float(st.max())
            medium = {
                "type": "homogeneous",
                "sigma_t": {"type": "rgb", "value": (st / scale).tolist()},
                "albedo": {"type": "rgb", "value": albedo.tolist()},
                "scale": scale,
            }
            if abs(mat["g"]) > 0.0:
                medium["phase"] = {"type": "hg", "g": mat["g"]}
            shape["bsdf"] = {
                "type": "dielectric",
                "int_ior": mat["eta"],
                "ext_ior": 1.0,
            }
            shape["interior"] = medium
        else:
            shape["bsdf"] = {
                "type": "diffuse",
                "reflectance": {"type": "rgb", "value": mat["albedo"]},
            }
        scene[f"object_{i}"] = shape

    return scene


if __name__ == "__main__":
    main()
