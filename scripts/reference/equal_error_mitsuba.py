#!/usr/bin/env python3
"""Equal-error time against Mitsuba 3 (issue 30; docs/performance.md, "Speed at equal error"): the Lambertian
Cornell box of cornell_mitsuba.py, direct light only, rendered by strata (its default sampler and primary mode,
`--bounces 0`) and by Mitsuba 3's `direct` integrator (`llvm_ad_rgb`, multijitter sampler; one emitter and one
BSDF sample per pixel sample, MIS), both as whole processes on the same cores, in one run.

Error: relative RMSE of the linear RGB image outside the light itself (pixels whose reference luminance is under
0.5, and not within 3 pixels of one over it; the light's is 12.5) against each renderer's own 1024-spp reference, so that only noise is measured:
sqrt(mean((x - ref)^2)) / mean(ref). The reference's own noise is taken out (an N-spp error squared over-counts by
the reference's, N/1024 of it). Strata's time to reach Mitsuba's error at N spp: its time fitted as a + b·spp
over the runs (the least of --repeats each), at N·(strata's error / Mitsuba's)² spp.

Not part of the test suite (it needs `pip install mitsuba OpenEXR numpy scipy` and Debian's libllvm19). Run from the
repository root after `cargo build --release`:

    python3 scripts/reference/equal_error_mitsuba.py [--size 512] [--spp 16 64] [--strata target/release/strata]
        [--shading-samples K] [--emitter-samples K]

With --shading-samples K strata renders N/K camera samples of K paths each (`--shading-samples`), so that both
renderers take N light samples per pixel at "N spp"; --emitter-samples K gives Mitsuba's `direct` integrator
N/K camera samples of K emitter and K BSDF samples each, its own way to do the same.
"""
import argparse
import json
import os
import sys
import tempfile

import numpy as np
from scipy.ndimage import binary_dilation

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cornell_mitsuba as cornell  # noqa: E402
from equal_error import equal_error_table, relative_rmse as masked_relative_rmse, run_timed  # noqa: E402

REFERENCE_SPP = 1024
LUMA = np.array([0.2126, 0.7152, 0.0722])

MITSUBA_CHILD = r"""
import sys, time, json
import numpy as np
import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
sys.path.insert(0, sys.argv[1])
import cornell_mitsuba as cornell
size, spp, seed, out, k = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5], int(sys.argv[6])
integrator = {"type": "direct", "emitter_samples": k, "bsdf_samples": k}
scene = cornell.mitsuba_scene_dict(size, spp // k, integrator=integrator, sampler="multijitter")
image = mi.render(mi.load_dict(scene), seed=seed)
np.save(out, np.array(image)[..., :3].astype(np.float64))
"""


def strata_image(strata, gltf, size, spp, seed, out, paths=1):
    seconds = run_timed([strata, "render", gltf, "--size", f"{size}x{size}", "--spp", str(spp // paths),
                         "--shading-samples", str(paths), "--seed", str(seed), "--bounces", "0",
                         "--background", "0,0,0", "-o", out, "--quiet"])
    return cornell.read_exr_rgb(out), seconds


def mitsuba_image(size, spp, seed, out, emitter_samples=1):
    here = os.path.dirname(os.path.abspath(__file__))
    seconds = run_timed([sys.executable, "-c", MITSUBA_CHILD, here, str(size), str(spp), str(seed), out,
                         str(emitter_samples)])
    return np.load(out), seconds


def relative_rmse(image, reference, spp):
    # Outside the light and the pixels its edge covers in part (walls stay under 0.5, the light is 12.5): the
    # edge pixels' coverage noise is the same for both renderers and would swamp the shading noise measured.
    mask = ~binary_dilation(reference @ LUMA > 0.5, iterations=3)
    return masked_relative_rmse(image, reference, spp, REFERENCE_SPP, mask)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64])
    parser.add_argument("--strata", default="target/release/strata")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs of each; the least counts")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.add_argument("--shading-samples", type=int, default=1, help="strata's paths per camera sample")
    parser.add_argument("--emitter-samples", type=int, default=1, help="Mitsuba's emitter (and BSDF) samples per "
                        "camera sample")
    args = parser.parse_args()
    rows = {"strata": {}, "Mitsuba": {}}
    with tempfile.TemporaryDirectory() as tmp:
        gltf = os.path.join(tmp, "lambertian-cornell.gltf")
        cornell.write_gltf(gltf)
        # Warm both: Mesa's shader cache and Dr.Jit's kernel cache, so neither pays a compile the other does not.
        strata_image(args.strata, gltf, 16, 1, 7, os.path.join(tmp, "warm.exr"))
        mitsuba_image(16, 1, 7, os.path.join(tmp, "warm.npy"))
        s_ref, _ = strata_image(args.strata, gltf, args.size, REFERENCE_SPP, 1, os.path.join(tmp, "sref.exr"))
        m_ref, _ = mitsuba_image(args.size, REFERENCE_SPP, 1, os.path.join(tmp, "mref.npy"))
        for spp in args.spp:
            # Times are the least of three runs (this machine is shared); errors from the first.
            k, e = args.shading_samples, args.emitter_samples
            s, ts = strata_image(args.strata, gltf, args.size, spp, 2, os.path.join(tmp, f"s{spp}.exr"), k)
            m, tm = mitsuba_image(args.size, spp, 2, os.path.join(tmp, f"m{spp}.npy"), e)
            for _ in range(args.repeats - 1):
                ts = min(ts, strata_image(args.strata, gltf, args.size, spp, 2, os.path.join(tmp, "t.exr"), k)[1])
                tm = min(tm, mitsuba_image(args.size, spp, 2, os.path.join(tmp, "t.npy"), e)[1])
            rows["strata"][spp] = (ts, relative_rmse(s, s_ref, spp))
            rows["Mitsuba"][spp] = (tm, relative_rmse(m, m_ref, spp))
    print(f"{args.size}x{args.size}, direct light; strata --shading-samples {args.shading_samples}, Mitsuba "
          f"emitter_samples {args.emitter_samples}")
    a, b, runs = equal_error_table(rows, "Mitsuba")
    result = {"size": args.size, "runs": runs, "strata_fit": {"startup_s": a, "per_spp_s": b},
              "shading_samples": args.shading_samples, "emitter_samples": args.emitter_samples}
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    sys.exit(main())
