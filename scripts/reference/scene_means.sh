#!/usr/bin/env bash
# Mean luminance of every scene in scenes/ rendered by two strata binaries (say, before and after a change), with
# Cook's effects alone and with --indirect, at half size and 64 spp. Needs python3 with OpenEXR and numpy.
#   scripts/reference/scene_means.sh OLD_BINARY NEW_BINARY
set -euo pipefail
cd "$(dirname "$0")/../.."
old=${1:?usage: scene_means.sh OLD_BINARY NEW_BINARY}; new=${2:?usage: scene_means.sh OLD_BINARY NEW_BINARY}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
mean() { python3 -c "
import OpenEXR, sys, numpy as np
with OpenEXR.File(sys.argv[1]) as f:
    ch = f.channels(); a = ch['RGBA'].pixels if 'RGBA' in ch else np.stack([ch[k].pixels for k in 'RGB'], -1)
print(f'{(a[..., :3].astype(np.float64) @ np.array([0.2126, 0.7152, 0.0722])).mean():.5f}')" "$1"; }
for s in cornell:256x256 dof:480x270 motion:480x270 showcase:480x270 soft-shadows:400x250; do
  name=${s%%:*}; size=${s##*:}
  for mode in "" --indirect; do
    line="$name ${mode:-direct}:"
    for bin in "$old" "$new"; do
      "$bin" render "scenes/$name.toml" --size "$size" --spp 64 $mode -o "$tmp/out.exr" --quiet
      line="$line $(mean "$tmp/out.exr")"
    done
    echo "$line"
  done
done
