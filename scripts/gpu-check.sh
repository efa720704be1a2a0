#!/usr/bin/env bash
# strata on one GPU, in one go: the device as strata sees it, the optics and frame tests that run there, the
# showcase at 1920x1080 with 64 spp (time, rays/s, and its difference from a reference picture), `strata check`,
# the frame benchmark, and a short report. Made for a machine with an NVIDIA GPU and its driver (an H100 or H200 traces with
# ray-tracing pipelines: they have no ray queries), and proven on lavapipe with `--device llvmpipe`.
#
#   scripts/gpu-check.sh [--device NAME|INDEX] [--out DIR] [--prebuilt DIR] [--reference PNG] [--quick]
#
# --prebuilt DIR  use the binaries in DIR (strata and the test binary, as `--pack DIR` leaves them) instead of
#                 building: for a GPU machine without a Rust toolchain. `scripts/gpu-check.sh --pack DIR` builds
#                 them here (release strata and the test binary, whose distributed and render_frames tests run
#                 there) and writes the repository path the tests were built in, which they read their scenes from.
# --reference PNG the showcase as another device rendered it at the same settings (lavapipe's, say), to compare
#                 means and regions with (python3 with numpy and pillow; the report says when it could not).
# --quick         a 480x270 showcase and a small benchmark: for proving the script on lavapipe in minutes.
#
# Finding Vulkan: the loader (libvulkan.so.1) must be installed or unpacked (the script says so when it is not);
# the NVIDIA driver's ICD is found through VK_DRIVER_FILES or VK_ICD_FILENAMES when set, else at the paths
# NVIDIA's packages and containers use (/usr/share/vulkan/icd.d, /etc/vulkan/icd.d,
# /usr/local/nvidia/share/vulkan/icd.d: nvidia_icd.json). The tests need the Khronos validation layer (unpack the
# vulkan-validationlayers package where it is not installed; VK_LAYER_PATH names its manifest folder).
# Exit status: 0 when every step passed, 1 when one failed (the report says which), 2 on bad arguments.
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

device="" out="gpu-check" prebuilt="" reference="" quick=0 pack=""
while [ $# -gt 0 ]; do
    case "$1" in
        --device) device="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        --prebuilt) prebuilt="$2"; shift 2 ;;
        --reference) reference="$2"; shift 2 ;;
        --quick) quick=1; shift ;;
        --pack) pack="$2"; shift 2 ;;
        -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "gpu-check: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done

# The test binaries cargo built last, by name (cargo test --no-run prints their paths).
pack_binaries() {
    local dir="$1"
    mkdir -p "$dir" || exit 1
    cargo build --release --locked || exit 1
    cp target/release/strata "$dir/" || exit 1
    local listing
    listing=$(cargo test --locked --no-run --test suite 2>&1) || { echo "$listing"; exit 1; }
    local bin
    bin=$(echo "$listing" | sed -n "s/.*Executable tests\/suite\.rs (\(.*\))/\1/p" | tail -1)
    [ -n "$bin" ] || { echo "gpu-check: cargo printed no path for the test binary" >&2; exit 1; }
    # Without its line tables the binary fits the device machine's transfer limit beside strata.
    strip --strip-debug -o "$dir/suite" "$bin" || exit 1
    echo "$repo" > "$dir/built-in"
    echo "gpu-check: packed strata and the test binary into $dir ($(du -sh "$dir" | cut -f1))"
}
if [ -n "$pack" ]; then
    pack_binaries "$pack"
    exit 0
fi

mkdir -p "$out"
report="$out/report.md"
failed=()
note() { echo "$*" | tee -a "$report"; }
: > "$report"
note "# strata GPU check, $(date -u +%Y-%m-%dT%H:%MZ)"
note ""

# Vulkan: the loader, then the driver's ICD.
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1'; then
    note "- no Vulkan loader (libvulkan.so.1): install libvulkan1, or unpack its .deb (dpkg -x libvulkan1_*.deb /; ldconfig)"
    exit 1
fi
if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ]; then
    for icd in /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
               /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json; do
        if [ -f "$icd" ]; then export VK_DRIVER_FILES="$icd"; break; fi
    done
fi
note "- Vulkan driver manifests: ${VK_DRIVER_FILES:-${VK_ICD_FILENAMES:-the default search of the loader, no NVIDIA ICD at the usual paths}}"
command -v nvidia-smi >/dev/null && note "- $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1)"

# The binaries: prebuilt, or built here.
if [ -n "$prebuilt" ]; then
    bin="$prebuilt"
    built_in=$(cat "$bin/built-in" 2>/dev/null || true)
    # The tests read scenes through the path they were built in; point it at this checkout.
    if [ -n "$built_in" ] && [ "$built_in" != "$repo" ] && [ ! -e "$built_in" ]; then
        mkdir -p "$(dirname "$built_in")" && ln -s "$repo" "$built_in"
    fi
else
    bin="$out/bin"
    pack_binaries "$bin" > "$out/build.log" 2>&1 || { note "- build failed: see $out/build.log"; exit 1; }
fi
strata="$bin/strata"
dev_args=()
[ -n "$device" ] && dev_args=(--device "$device")

step() {  # step NAME LOG COMMAND...: runs it, notes pass or fail with the time it took
    local name="$1" log="$2"; shift 2
    local start=$SECONDS
    if "$@" > "$log" 2>&1; then
        note "- $name: passed ($((SECONDS - start)) s)"
    else
        note "- $name: FAILED ($((SECONDS - start)) s, exit $?; see $(basename "$log"))"
        failed+=("$name")
    fi
}

step "strata info" "$out/info.txt" "$strata" info
note ""
note '```'
sed 's/^/    /' "$out/info.txt" | tee -a "$report"
note '```'

export STRATA_TEST_DEVICE="$device"
for t in distributed render_frames; do
    step "tests/$t.rs (validation layer; every frame on each way to trace the device has)" "$out/test-$t.txt" \
        "$bin/suite" "$t::" --test-threads 1
    grep -E '^test result' "$out/test-$t.txt" | sed 's/^/  /' | tee -a "$report"
done

if [ "$quick" = 1 ]; then size=480x270 spp=16 bench=(--size 64x64 --spp 4); else size=1920x1080 spp=64 bench=(); fi
showcase="$out/showcase.png"
step "showcase $size, $spp spp" "$out/showcase.json" \
    "$strata" render scenes/showcase.toml --size "$size" --spp "$spp" -o "$showcase" --json --quiet "${dev_args[@]}"
if [ -s "$out/showcase.json" ]; then
    python3 - "$out/showcase.json" <<'EOF' | tee -a "$report"
import json, sys
s = json.load(open(sys.argv[1]))
print(f"  {s['device']}, --trace {s['trace']}: {s['render_seconds']:.2f} s rendering ({s['seconds']:.2f} s in all), "
      f"{s['samples_per_second']:.2f} samples/s, {s['rays_per_second'] / 1e6:.1f} M rays/s")
EOF
fi
if [ -n "$reference" ]; then
    if python3 -c 'import numpy, PIL' 2>/dev/null; then
        step "showcase against $reference" "$out/compare.txt" python3 scripts/reference/compare_images.py "$showcase" "$reference"
        sed 's/^/  /' "$out/compare.txt" | tee -a "$report"
    else
        note "- showcase against $reference: not compared (python3 lacks numpy or pillow)"
    fi
fi

# The render check suite against the goldens embedded in strata (made on lavapipe): on another device the exact
# tier has no hash, so the perceptual tier decides; its report.html shows every failing case.
step "strata check (the render check suite)" "$out/check.txt" \
    "$strata" check --out "$out/check" --junit "$out/check/junit.xml" "${dev_args[@]}"
tail -n 4 "$out/check.txt" | sed 's/^/  /' | tee -a "$report"

step "strata bench (frame)" "$out/bench.txt" "$strata" bench --only frame "${bench[@]}" "${dev_args[@]}"
grep -E '^scenes/|pipeline creation|ways to trace|samples/s' "$out/bench.txt" | sed 's/^/  /' | tee -a "$report"

note ""
if [ ${#failed[@]} -eq 0 ]; then
    note "All steps passed."
    exit 0
fi
note "Failed: ${failed[*]}"
exit 1
