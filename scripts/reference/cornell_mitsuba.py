#!/usr/bin/env python3
"""An independent reference for strata's light transport: the Cornell box of `scenes/cornell.toml` (geometry,
albedos, the one-sided ceiling light 1 mm under the ceiling, the camera) with purely Lambertian walls and no bump
maps, rendered by strata and by Mitsuba 3's path tracer, compared band by band: the direct light (strata
`--bounces 0`, Mitsuba max_depth 2) and the light that arrives by one diffuse bounce (`--bounces 1` minus
`--bounces 0`, Mitsuba max_depth 3 minus 2).

Not part of the test suite (it needs `pip install mitsuba OpenEXR numpy`; the scalar_rgb variant needs no LLVM).
Run from the repository root after `cargo build --release`:

    python3 scripts/reference/cornell_mitsuba.py [--spp 1024] [--size 96] [--strata target/release/strata]

At 96×96 and 1024 spp (under a minute on 2 cores) band ratios scatter by about ±1% (±4% in the top bands'
one-bounce light, where Mitsuba's max_depth 3 − 2 difference is noisiest).
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np

WALLS = [  # name, centre, normal, albedo
    ("floor", (0.0, 0.0, 0.0), (0, 1, 0), (0.73, 0.73, 0.73)),
    ("ceiling", (0.0, 2.0, 0.0), (0, -1, 0), (0.73, 0.73, 0.73)),
    ("back wall", (0.0, 1.0, -1.0), (0, 0, 1), (0.73, 0.73, 0.73)),
    ("left wall", (-1.0, 1.0, 0.0), (1, 0, 0), (0.63, 0.065, 0.05)),
    ("right wall", (1.0, 1.0, 0.0), (-1, 0, 0), (0.14, 0.45, 0.091)),
]
BOXES = [  # name, centre, half extents, rotation about +Y (radians)
    ("tall box", (-0.33, 0.6, -0.3), (0.3, 0.6, 0.3), 0.3),
    ("short box", (0.35, 0.3, 0.35), (0.3, 0.3, 0.3), -0.3),
]
LIGHT = {"centre": (0.0, 1.999, 0.0), "size": 0.5, "radiance": (17.0, 12.0, 4.0)}
CAMERA = {"origin": (0.0, 1.0, 3.9), "target": (0.0, 1.0, 0.0), "yfov_degrees": 39.0}


def square(centre, normal, size):
    """Corners of a size×size square at centre facing normal (one of ±X, ±Y, ±Z), counter-clockwise seen from
    its front."""
    n = np.array(normal, float)
    a = np.array([0, 0, 1.0]) if abs(n[1]) > 0.5 else np.array([0, 1.0, 0])
    u = np.cross(a, n)
    v = np.cross(n, u)
    h = size / 2
    c = np.array(centre, float)
    return [c - h * u - h * v, c + h * u - h * v, c + h * u + h * v, c - h * u + h * v]


def box_faces(centre, half, angle):
    ca, sa = math.cos(angle), math.sin(angle)
    rot = np.array([[ca, 0, sa], [0, 1, 0], [-sa, 0, ca]])
    faces = []
    for axis in range(3):
        for sign in (-1, 1):
            n = np.zeros(3)
            n[axis] = sign
            others = [i for i in range(3) if i != axis]
            u = np.zeros(3)
            v = np.zeros(3)
            u[others[0]] = half[others[0]]
            v[others[1]] = half[others[1]]
            if np.dot(np.cross(u, v), n) < 0:
                u, v = v, u
            c = n * half[axis]
            corners = [c - u - v, c + u - v, c + u + v, c - u + v]
            faces.append(([rot @ p + np.array(centre) for p in corners], rot @ n))
    return faces


def write_gltf(path):
    """The Lambertian box as a glTF with KHR_materials_specular factor 0 (strata's Lambertian surface)."""
    blob = bytearray()
    accessors, views, meshes, nodes, materials = [], [], [], [], []

    def add(data, fmt, count, kind, target, minmax=None):
        offset = len(blob)
        blob.extend(struct.pack("<" + fmt * (len(data) // len(fmt)), *data))
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(data) * 4, "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": 5126 if fmt == "f" else 5125, "count": count,
               "type": kind}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def material(name, albedo, emission=None):
        m = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(albedo) + [1.0], "metallicFactor": 0.0,
                                                    "roughnessFactor": 1.0},
             "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
        if emission:
            peak = max(emission)
            m["emissiveFactor"] = [e / peak for e in emission]
            m["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": peak}
        materials.append(m)
        return len(materials) - 1

    def mesh(name, quads, mat):
        positions, normals, indices = [], [], []
        for corners, n in quads:
            base = len(positions) // 3
            for p in corners:
                positions += [float(x) for x in p]
                normals += [float(x) for x in n]
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
        pts = np.array(positions).reshape(-1, 3)
        pos = add(positions, "f", len(pts), "VEC3", 34962, (pts.min(0).tolist(), pts.max(0).tolist()))
        nor = add(normals, "f", len(pts), "VEC3", 34962)
        idx = add(indices, "I", len(indices), "SCALAR", 34963)
        meshes.append({"name": name, "primitives": [{"attributes": {"POSITION": pos, "NORMAL": nor},
                                                      "indices": idx, "material": mat}]})
        nodes.append({"name": name, "mesh": len(meshes) - 1})

    for name, centre, normal, albedo in WALLS:
        mesh(name, [(square(centre, normal, 2.0), normal)], material(name, albedo))
    mesh("ceiling light", [(square(LIGHT["centre"], (0, -1, 0), LIGHT["size"]), (0, -1, 0))],
         material("ceiling light", (0.0, 0.0, 0.0), LIGHT["radiance"]))
    for name, centre, half, angle in BOXES:
        mesh(name, box_faces(centre, half, angle), material(name, (0.73, 0.73, 0.73)))
    nodes.append({"name": "camera", "camera": 0, "translation": list(CAMERA["origin"])})
    doc = {
        "asset": {"version": "2.0", "generator": "strata scripts/reference/cornell_mitsuba.py"},
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_emissive_strength"],
        "scene": 0, "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": meshes,
        "materials": materials, "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": os.path.basename(path)[:-5] + ".bin"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": math.radians(CAMERA["yfov_degrees"]),
                                                             "aspectRatio": 1.0, "znear": 0.01}}],
    }
    with open(path[:-5] + ".bin", "wb") as f:
        f.write(blob)
    with open(path, "w") as f:
        json.dump(doc, f)


def mitsuba_scene_dict(size, spp, integrator, sampler="independent"):
    """The box as a Mitsuba 3 scene dictionary (a variant must be set)."""
    import mitsuba as mi
    T = mi.ScalarTransform4f

    def rect(centre, normal, size, bsdf, emitter=None):
        # Mitsuba's rectangle is [-1, 1]² in XY facing +Z.
        n = normal
        if n == (0, 1, 0):
            r = T().rotate([1, 0, 0], -90)
        elif n == (0, -1, 0):
            r = T().rotate([1, 0, 0], 90)
        elif n == (1, 0, 0):
            r = T().rotate([0, 1, 0], 90)
        elif n == (-1, 0, 0):
            r = T().rotate([0, 1, 0], -90)
        else:
            r = T()
        shape = {"type": "rectangle", "to_world": T().translate(list(centre)) @ r @ T().scale(size / 2), "bsdf": bsdf}
        if emitter:
            shape["emitter"] = emitter
        return shape

    def diffuse(albedo):
        return {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(albedo)}}

    scene = {"type": "scene", "integrator": integrator,
             "sensor": {"type": "perspective", "fov": CAMERA["yfov_degrees"], "fov_axis": "y",
                        "to_world": T().look_at(origin=list(CAMERA["origin"]), target=list(CAMERA["target"]),
                                                up=[0, 1, 0]),
                        "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
                        "sampler": {"type": sampler, "sample_count": spp}}}
    for name, centre, normal, albedo in WALLS:
        scene[name.replace(" ", "_")] = rect(centre, normal, 2.0, diffuse(albedo))
    scene["light"] = rect(LIGHT["centre"], (0, -1, 0), LIGHT["size"], diffuse((0, 0, 0)),
                          {"type": "area", "radiance": {"type": "rgb", "value": list(LIGHT["radiance"])}})
    for name, centre, half, angle in BOXES:
        scene[name.replace(" ", "_")] = {
            "type": "cube", "bsdf": diffuse((0.73, 0.73, 0.73)),
            "to_world": T().translate(list(centre)) @ T().rotate([0, 1, 0], math.degrees(angle)) @ T().scale(list(half))}
    return scene


def mitsuba_render(size, spp, max_depth):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    image = mi.render(mi.load_dict(mitsuba_scene_dict(size, spp, {"type": "path", "max_depth": max_depth})))
    return np.array(image)[..., :3].astype(np.float64)


def read_exr_rgb(path):
    import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        a = ch["RGBA"].pixels if "RGBA" in ch else np.stack([ch[k].pixels for k in "RGB"], -1)
    return a[..., :3].astype(np.float64)


def strata_render(strata, gltf, size, spp, bounces, out):
    subprocess.run([strata, "render", gltf, "--size", f"{size}x{size}", "--spp", str(spp),
                    "--sampler", "random", "--primary", "rays", "--indirect", "--bounces", str(bounces),
                    "--background", "0,0,0", "-o", out, "--quiet"], check=True)
    return read_exr_rgb(out)


def bands(image, n=8):
    lum = image @ np.array([0.2126, 0.7152, 0.0722])
    return [lum[i * len(lum) // n:(i + 1) * len(lum) // n].mean() for i in range(n)]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spp", type=int, default=1024)
    parser.add_argument("--size", type=int, default=96)
    parser.add_argument("--strata", default="target/release/strata", help="the strata binary to compare")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        gltf = os.path.join(tmp, "lambertian-cornell.gltf")
        write_gltf(gltf)
        s0 = strata_render(args.strata, gltf, args.size, args.spp, 0, os.path.join(tmp, "s0.exr"))
        s1 = strata_render(args.strata, gltf, args.size, args.spp, 1, os.path.join(tmp, "s1.exr"))
    m2 = mitsuba_render(args.size, args.spp, 2)
    m3 = mitsuba_render(args.size, args.spp, 3)
    print(f"mean luminance, direct: strata {bands(s0, 1)[0]:.5f} mitsuba {bands(m2, 1)[0]:.5f}")
    print(f"mean luminance, one bounce: strata {bands(s1 - s0, 1)[0]:.5f} mitsuba {bands(m3 - m2, 1)[0]:.5f}")
    print("band (top to bottom): direct strata/mitsuba, one-bounce strata/mitsuba")
    for i, (a, b, c, d) in enumerate(zip(bands(s0), bands(m2), bands(s1 - s0), bands(m3 - m2))):
        print(f"  {i}: {a / b if b > 0 else float('nan'):.4f}  {c / d if d > 0 else float('nan'):.4f}")


if __name__ == "__main__":
    sys.exit(main())
