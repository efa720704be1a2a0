#!/usr/bin/env bash
# Installs what strata needs on a Debian/Ubuntu machine and checks that the Vulkan driver can do ray queries.
# Idempotent. Runs as root, or re-runs itself through sudo.
#
# What it installs and why:
#   - Vulkan loader + headers, the Khronos validation layer, vulkaninfo  (running and testing)
#   - Mesa's lavapipe with VK_KHR_ray_query and VK_KHR_ray_tracing_pipeline (Debian 12's own Mesa 22.3 lacks
#     them; bookworm-backports has 25.x)
#   - libshaderc-dev, glslang-dev, spirv-tools (static archives the build links; see build/shaderc-link)
#   - pkg-config, a C/C++ toolchain (the shaderc crate builds a small C++ shim)
#   - python3 with venv and pip: the Python package (`pip install .` in a virtual environment, README)
#   - with --denoiser: Intel Open Image Denoise for `strata render --denoise`, unpacked from the PyPI wheel pyoidn
#     (pinned, checksum verified) into /opt/strata/oidn/lib; there is no Debian package. strata loads it at run
#     time, so builds and tests without it stay green.
# It never names a mirror: the backports suite is added on the URI the machine's own apt sources already use.
set -euo pipefail

if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null; then exec sudo -E bash "$0" "$@"; fi
  echo "setup.sh: must run as root (or with sudo available)" >&2
  exit 1
fi

export DEBIAN_FRONTEND=noninteractive
. /etc/os-release
echo "setup: ${PRETTY_NAME:-unknown system}"

# The base packages, from the distribution's main archive. `--runtime` (a container that only runs a built
# strata, deploy/container/Dockerfile) takes the Vulkan loader, the layer and vulkaninfo, not the build tools.
base_pkgs=(libvulkan1 libvulkan-dev vulkan-validationlayers vulkan-tools
           libshaderc-dev glslang-dev glslang-tools spirv-tools
           pkg-config build-essential ca-certificates
           python3 python3-venv python3-pip)
runtime_only=
denoiser=
for arg in "$@"; do
  case "$arg" in
    --runtime)
      runtime_only=1
      base_pkgs=(libvulkan1 vulkan-validationlayers vulkan-tools ca-certificates);;
    --denoiser) denoiser=1;;
    *) echo "setup.sh: unknown option $arg (--runtime, --denoiser)" >&2; exit 2;;
  esac
done

# Open Image Denoise from the pyoidn wheel: its CPU device, core and TBB libraries, nothing of Python's.
OIDN_DIR=/opt/strata/oidn/lib
OIDN_WHEEL=pyoidn-2.5.1.0-py3-none-manylinux2014_x86_64.whl
OIDN_SHA256=32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e
install_denoiser() {
  if [ -e "$OIDN_DIR/libOpenImageDenoise.so.2" ] && [ -e "$OIDN_DIR/libOpenImageDenoise_device_cpu.so.2.5.1" ]; then
    echo "setup: Open Image Denoise: $OIDN_DIR (already there)"
    return
  fi
  apt-get install -y -qq --no-install-recommends python3 python3-pip
  local tmp
  tmp=$(mktemp -d)
  python3 -m pip download --quiet --no-deps --only-binary=:all: --dest "$tmp" "pyoidn==2.5.1.0"
  echo "$OIDN_SHA256  $tmp/$OIDN_WHEEL" | sha256sum --check --quiet
  mkdir -p "$OIDN_DIR"
  python3 - "$tmp/$OIDN_WHEEL" "$OIDN_DIR" <<'PY'
import os, re, sys, zipfile
wheel, out = sys.argv[1], sys.argv[2]
keep = re.compile(r"^pyoidn/oidn/lib/(libOpenImageDenoise(\.so.*|_core\.so.*|_device_cpu\.so.*)|libtbb\.so.*)$")
with zipfile.ZipFile(wheel) as z:
    for entry in z.infolist():
        if keep.match(entry.filename):
            with z.open(entry) as src, open(os.path.join(out, os.path.basename(entry.filename)), "wb") as dst:
                dst.write(src.read())
PY
  rm -rf "$tmp"
  echo "setup: Open Image Denoise: $OIDN_DIR"
}

have_ray_query() {
  command -v vulkaninfo >/dev/null || return 1
  # capture first: with pipefail, grep -q closing the pipe early would fail the check
  local out
  out=$(VK_DRIVER_FILES=$(lvp_icd) vulkaninfo 2>/dev/null) || return 1
  [[ "$out" == *VK_KHR_ray_query* ]]
}
# Both ways strata traces: the test suite holds ray queries and ray-tracing pipelines to the same bits.
have_rt_pipeline() {
  command -v vulkaninfo >/dev/null || return 1
  local out
  out=$(VK_DRIVER_FILES=$(lvp_icd) vulkaninfo 2>/dev/null) || return 1
  [[ "$out" == *VK_KHR_ray_tracing_pipeline* ]]
}
lvp_icd() { ls /usr/share/vulkan/icd.d/lvp_icd*.json 2>/dev/null | head -n1; }

apt-get update -qq
apt-get install -y -qq --no-install-recommends "${base_pkgs[@]}" mesa-vulkan-drivers

if ! have_ray_query && [ "${ID:-}" = debian ] && [ "${VERSION_CODENAME:-}" = bookworm ]; then
  # Debian 12: take Mesa from bookworm-backports on the mirror the machine already uses.
  uri=""
  for f in /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    uri=$(awk '/^URIs:/{print $2; exit}' "$f")
    # skip the security archive; we want the main one
    case "$uri" in *security*) uri="";; *) [ -n "$uri" ] && break;; esac
  done
  if [ -z "$uri" ] && [ -f /etc/apt/sources.list ]; then
    uri=$(awk '$1=="deb" && $0 !~ /security/ {for(i=2;i<=NF;i++) if ($i ~ /^[a-z]+:\/\//) {print $i; exit}}' /etc/apt/sources.list)
  fi
  if [ -z "$uri" ]; then
    echo "setup: could not find the apt mirror URI in /etc/apt/sources.list(.d); add bookworm-backports by hand" >&2
    exit 1
  fi
  list=/etc/apt/sources.list.d/strata-backports.list
  line="deb $uri bookworm-backports main"
  if [ "$(cat "$list" 2>/dev/null)" != "$line" ]; then
    echo "setup: adding bookworm-backports from $uri"
    echo "$line" > "$list"
  fi
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers
fi

# Check, not hope: the lavapipe ICD must report ray queries.
icd=$(lvp_icd)
if [ -z "$icd" ]; then
  echo "setup: FAILED: no lavapipe ICD under /usr/share/vulkan/icd.d" >&2
  exit 1
fi
summary=$(VK_DRIVER_FILES="$icd" vulkaninfo --summary 2>/dev/null || true)
device=$(printf '%s\n' "$summary" | awk -F'= ' '/deviceName/{print $2; exit}')
driver=$(printf '%s\n' "$summary" | awk -F'= ' '/driverInfo/{print $2; exit}')
mesa=$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || echo unknown)
layer=$(dpkg-query -W -f='${Version}' vulkan-validationlayers 2>/dev/null || echo missing)
if have_ray_query; then rq=yes; else rq=no; fi
if have_rt_pipeline; then rtp=yes; else rtp=no; fi
echo "setup: device:            ${device:-none found}"
echo "setup: driver:            ${driver:-unknown}"
echo "setup: mesa package:      $mesa"
echo "setup: validation layer:  $layer"
echo "setup: VK_KHR_ray_query:  $rq"
echo "setup: VK_KHR_ray_tracing_pipeline: $rtp"
if [ "$rq" != yes ] || [ "$rtp" != yes ]; then
  echo "setup: FAILED: lavapipe lacks VK_KHR_ray_query or VK_KHR_ray_tracing_pipeline; the tests need a Mesa" \
       "with both (25.0+)" >&2
  exit 1
fi
# Rust is the user's (rustup); Debian 12's own cargo is too old for strata's dependencies.
if [ -n "$runtime_only" ]; then
  :
elif command -v cargo >/dev/null; then
  echo "setup: cargo:             $(cargo --version)"
else
  echo "setup: note: no cargo on PATH; install Rust 1.85 or newer (rustup) to build strata" >&2
fi
if [ -n "$denoiser" ]; then
  install_denoiser
fi
echo "setup: OK"
