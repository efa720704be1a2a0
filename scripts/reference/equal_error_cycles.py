#!/usr/bin/env python3
"""Equal-error time against Blender's Cycles (issue 30; docs/performance.md, "Speed at equal error"): a glTF
asset under an HDR sky, path traced (8 bounces, diffuse interreflection on), rendered by strata (its default
sampler) and by Cycles 4.2 on the CPU (bpy), both as whole processes on the same cores, in one run.

The sky is written by this script: an equirectangular OpenEXR whose radiance depends on elevation alone (a blue
gradient over a darker ground and a sun disk of radius 4 degrees at the zenith), so the two renderers' azimuth
conventions cannot make their lighting differ; both put +Y (Blender's +Z after its glTF import) at the image's top
row. Cycles runs unbiased and as strata filters: a 1-pixel box filter, no adaptive sampling, no denoising, no
clamping, no glossy filter, caustics on; 8 bounces of every kind.

Error: relative RMSE of the linear RGB image against each renderer's own reference of --reference-spp samples, so
that only noise is measured and neither renderer's bias counts: sqrt(mean((x - ref)^2)) / mean(ref), the
reference's own noise taken out (an N-spp error squared over-counts by the reference's, N/reference of it).
Strata's time to reach Cycles' error at N spp: its whole-process time fitted as a + b*spp over the runs (the least
of --repeats each), at N*(strata's error / Cycles')^2 spp.

Not part of the test suite. It needs Python 3.11 with `pip install bpy==4.2.0 numpy OpenEXR` (bpy is built for
3.11 alone; a virtual environment keeps it apart: `python3.11 -m venv .venv-bpy`). Run from the repository root
after `cargo build --release`:

    .venv-bpy/bin/python scripts/reference/equal_error_cycles.py [--gltf scenes/showcase.gltf] [--size 256]
        [--spp 16 64] [--strata target/release/strata] [--shading-samples K]

--gltf takes any glTF or GLB Blender imports (its first camera frames both renders); the issue's FlightHelmet is
not in this repository (its textures are large), but any asset with a camera works the same way.
"""
import argparse
import json
import math
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from equal_error import equal_error_table, relative_rmse, run_timed  # noqa: E402

BOUNCES = 8

CYCLES_CHILD = r"""
import sys
import bpy
gltf, sky, size, spp, seed, out, bounces = sys.argv[1:8]
size, spp, seed, bounces = int(size), int(spp), int(seed), int(bounces)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=gltf)
scene = bpy.context.scene
cameras = [o for o in scene.objects if o.type == "CAMERA"]
if not cameras:
    sys.exit(f"{gltf} has no camera: the comparison frames both renders with the asset's first camera")
scene.camera = cameras[0]
world = bpy.data.worlds.new("sky")
scene.world = world
world.use_nodes = True
nodes = world.node_tree.nodes
environment = nodes.new("ShaderNodeTexEnvironment")
environment.image = bpy.data.images.load(sky)
environment.interpolation = "Linear"
world.node_tree.links.new(environment.outputs["Color"], nodes["Background"].inputs["Color"])
scene.render.engine = "CYCLES"
c = scene.cycles
c.device = "CPU"
c.samples = spp
c.seed = seed
c.use_adaptive_sampling = False
c.use_denoising = False
c.sample_clamp_direct = 0.0
c.sample_clamp_indirect = 0.0
c.blur_glossy = 0.0
c.caustics_reflective = True
c.caustics_refractive = True
c.max_bounces = bounces
c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = c.transparent_max_bounces = bounces
c.volume_bounces = 0
c.filter_type = "BOX"
c.filter_width = 1.0
scene.render.resolution_x = scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
scene.view_settings.exposure = 0.0
settings = scene.render.image_settings
settings.file_format = "OPEN_EXR"
settings.color_depth = "32"
settings.color_mode = "RGB"
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
# bpy 4.2 crashes in its own teardown at interpreter exit (SIGSEGV after the file is written): leave at once.
sys.stdout.flush()
import os
os._exit(0)
"""


def read_exr_rgb(path):
    import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        a = ch["RGBA"].pixels if "RGBA" in ch else (
            ch["RGB"].pixels if "RGB" in ch else np.stack([ch[k].pixels for k in "RGB"], -1))
    return a[..., :3].astype(np.float64)


def write_sky(path, width=512):
    """Radiance by elevation alone: a sun disk at the zenith, a blue sky over a darker ground."""
    import OpenEXR
    height = width // 2
    elevation = (0.5 - (np.arange(height) + 0.5) / height) * math.pi  # top row: straight up
    sky = np.where(elevation[:, None] >= 0.0,
                   np.array([0.35, 0.55, 1.0]) * (0.4 + 0.6 * np.sin(np.maximum(elevation, 0.0)))[:, None],
                   np.array([0.25, 0.22, 0.2]))
    sky = np.where(elevation[:, None] > math.radians(90 - 4), np.array([60.0, 55.0, 45.0]), sky)
    image = np.repeat(sky[:, None, :], width, axis=1).astype(np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": image}) as f:
        f.write(path)


def strata_image(strata, gltf, sky, size, spp, seed, out, paths=1):
    seconds = run_timed([strata, "render", gltf, "--environment", sky, "--indirect", "--bounces", str(BOUNCES),
                         "--size", f"{size}x{size}", "--spp", str(max(spp // paths, 1)), "--shading-samples",
                         str(paths), "--seed", str(seed), "-o", out, "--quiet"])
    return read_exr_rgb(out), seconds


def cycles_image(python, gltf, sky, size, spp, seed, out):
    seconds = run_timed([python, "-c", CYCLES_CHILD, gltf, sky, str(size), str(spp), str(seed), out,
                         str(BOUNCES)])
    return read_exr_rgb(out), seconds


def strata_alone(args, gltf, sky, tmp):
    """--strata-only: strata's least time and error per spp against its own reference, for comparing builds."""
    k = args.shading_samples
    ref, _ = strata_image(args.strata, gltf, sky, args.size, args.reference_spp, 1, os.path.join(tmp, "sref.exr"), k)
    for spp in args.spp:
        image, seconds = strata_image(args.strata, gltf, sky, args.size, spp, 2, os.path.join(tmp, f"s{spp}.exr"), k)
        for _ in range(args.repeats - 1):
            seconds = min(seconds, strata_image(args.strata, gltf, sky, args.size, spp, 2,
                                                os.path.join(tmp, "t.exr"), k)[1])
        error = relative_rmse(image, ref, spp, args.reference_spp)
        print(f"strata {args.strata}: {spp} spp {seconds:.2f} s, error {error:.4f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--gltf", default="scenes/showcase.gltf")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--strata", default="target/release/strata")
    parser.add_argument("--python", default=sys.executable, help="the Python that imports bpy (this one)")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs of each; the least counts")
    parser.add_argument("--shading-samples", type=int, default=1, help="strata's paths per camera sample")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.add_argument("--strata-only", action="store_true",
                        help="render strata alone and print its time and error per spp (to compare strata builds)")
    args = parser.parse_args()
    gltf = os.path.abspath(args.gltf)
    for path, what in ((gltf, "--gltf"), (args.strata, "--strata")):
        if not os.path.exists(path):
            sys.exit(f"equal_error_cycles: {what} {path} does not exist")
    rows = {"strata": {}, "Cycles": {}}
    k = args.shading_samples
    with tempfile.TemporaryDirectory() as tmp:
        sky = os.path.join(tmp, "sky.exr")
        write_sky(sky)
        # Warm both: Mesa's shader cache, and Blender's first start (add-ons, kernels), so neither pays a cost
        # once that the other does not.
        strata_image(args.strata, gltf, sky, 16, 1, 7, os.path.join(tmp, "warm.exr"))
        if args.strata_only:
            return strata_alone(args, gltf, sky, tmp)
        cycles_image(args.python, gltf, sky, 16, 1, 7, os.path.join(tmp, "warm-cycles.exr"))
        s_ref, _ = strata_image(args.strata, gltf, sky, args.size, args.reference_spp, 1,
                                os.path.join(tmp, "sref.exr"), k)
        c_ref, _ = cycles_image(args.python, gltf, sky, args.size, args.reference_spp, 1,
                                os.path.join(tmp, "cref.exr"))
        for spp in args.spp:
            s, ts = strata_image(args.strata, gltf, sky, args.size, spp, 2, os.path.join(tmp, f"s{spp}.exr"), k)
            c, tc = cycles_image(args.python, gltf, sky, args.size, spp, 2, os.path.join(tmp, f"c{spp}.exr"))
            for _ in range(args.repeats - 1):
                ts = min(ts, strata_image(args.strata, gltf, sky, args.size, spp, 2, os.path.join(tmp, "t.exr"),
                                          k)[1])
                tc = min(tc, cycles_image(args.python, gltf, sky, args.size, spp, 2,
                                          os.path.join(tmp, "t-cycles.exr"))[1])
            rows["strata"][spp] = (ts, relative_rmse(s, s_ref, spp, args.reference_spp))
            rows["Cycles"][spp] = (tc, relative_rmse(c, c_ref, spp, args.reference_spp))
        # How far the two references are apart: the same scene and light, each renderer's own conventions.
        means = (float(np.mean(s_ref)), float(np.mean(c_ref)))
    print(f"{args.gltf} under the sky, {args.size}x{args.size}, path traced ({BOUNCES} bounces); strata "
          f"--shading-samples {k}; reference means strata {means[0]:.4f}, Cycles {means[1]:.4f}")
    a, b, runs = equal_error_table(rows, "Cycles")
    result = {"gltf": args.gltf, "size": args.size, "bounces": BOUNCES, "shading_samples": k,
              "reference_means": {"strata": means[0], "cycles": means[1]},
              "strata_fit": {"startup_s": a, "per_spp_s": b}, "runs": runs}
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    sys.exit(main())
