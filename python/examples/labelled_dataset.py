#!/usr/bin/env python3
"""Renders a small labelled dataset: N views of a scene around a turntable, each saved as one .npz with the
colour (linear, float32), the display image (uint8), metric depth, instance and semantic labels, forward flow, and
the camera (K, pose) as JSON, in the layout Kubric and BOP users expect (docs/outputs.md).

    python3 python/examples/labelled_dataset.py scenes/cornell.toml out/dataset --views 8 --size 128x96 --spp 16
"""
import argparse
import json
import pathlib
import sys

import numpy as np

import strata


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", help="a .gltf/.glb file or a scene file (.toml)")
    parser.add_argument("out", help="directory for view_NNN.npz and view_NNN.json")
    parser.add_argument("--views", type=int, default=8, help="views around the turntable (default 8)")
    parser.add_argument("--size", default="128x96", help="WxH pixels (default 128x96)")
    parser.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    parser.add_argument("--elevation", type=float, default=20.0, help="camera elevation in degrees (default 20)")
    parser.add_argument("--denoise", action="store_true", help="denoise the colour (scripts/setup.sh --denoiser)")
    args = parser.parse_args(argv)
    if args.views < 1:
        parser.error("--views must be at least 1")
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        parser.error(f"--size {args.size!r}: give WxH, e.g. 128x96")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with strata.Renderer() as renderer:
        scene = renderer.load(args.scene)
        for view in range(args.views):
            theta = 360.0 * view / args.views
            frame = renderer.render(
                scene,
                size=(width, height),
                spp=args.spp,
                orbit=(theta, args.elevation),
                aovs=["depth", "instance", "semantic", "motion", "normal"],
                denoise=args.denoise,
                seed=view,
            )
            stem = out / f"view_{view:03d}"
            np.savez_compressed(
                stem.with_suffix(".npz"),
                color=frame["color"],
                display=frame["display"],
                depth=frame["depth"],
                instance=frame["instance"],
                semantic=frame["semantic"],
                motion=frame["motion"],
                normal=frame["normal"],
            )
            stem.with_suffix(".json").write_text(json.dumps(frame["camera"], indent=2) + "\n")
            labels = np.unique(frame["instance"])
            print(f"{stem}.npz: view {view + 1}/{args.views}, {len(labels[labels > 0])} instances seen", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
