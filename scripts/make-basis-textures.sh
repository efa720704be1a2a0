#!/usr/bin/env bash
# Makes the test suite's Basis Universal textures, tests/data/basis/: a small RGBA image (source.png), its two
# Basis Universal encodings as KTX2 files (etc1s.ktx2: ETC1S, BasisLZ-supercompressed; uastc.ktx2: UASTC,
# Zstandard-supercompressed), and what Binomial's reference transcoder gives for each as RGBA8
# (etc1s.reference.png, uastc.reference.png), which tests/gltf_features.rs holds strata's transcoding to, byte for
# byte. Encoder and transcoder are Binomial's basis_universal 1.16 (Apache-2.0): its `basisu` tool and a ten-line
# program over its `ktx2_transcoder`, built from the sources the basis-universal-sys crate vendors (the tool's own
# -unpack writes no RGBA32 image for KTX2 input). Run once; its outputs are committed. Needs cargo, cmake, a C++
# compiler and python3.
set -euo pipefail
out=$(cd "$(dirname "$0")/.." && pwd)/tests/data/basis
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The crate's sources, through Cargo's own registry client.
mkdir -p "$work/fetch/src" && cd "$work/fetch"
printf '[package]\nname = "fetch"\nversion = "0.0.0"\nedition = "2021"\n[dependencies]\nbasis-universal-sys = "=0.3.1"\n' >Cargo.toml
touch src/lib.rs
cargo fetch --quiet
vendor=$(cargo metadata --format-version 1 | python3 -c '
import json, os, sys
meta = json.load(sys.stdin)
path = next(p["manifest_path"] for p in meta["packages"] if p["name"] == "basis-universal-sys")
print(os.path.join(os.path.dirname(path), "vendor", "basis_universal"))')
cp -r "$vendor" "$work/basis_universal" && vendor=$work/basis_universal
cmake -S "$vendor" -B "$work/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" -j "$(nproc)" >/dev/null 2>&1
basisu=$vendor/bin/basisu

# The reference transcoder: a KTX2 file's base level as RGBA8 (transcoder_texture_format::cTFRGBA32).
cat >"$work/reference.cpp" <<'CPP'
#include "transcoder/basisu_transcoder.h"
#include <cstdio>
#include <vector>
int main(int argc, char **argv) {
    if (argc != 3) return 2;
    std::vector<unsigned char> in;
    FILE *f = std::fopen(argv[1], "rb");
    for (int c; f && (c = std::fgetc(f)) != EOF;) in.push_back((unsigned char)c);
    basist::basisu_transcoder_init();
    basist::ktx2_transcoder ktx2;
    if (!ktx2.init(in.data(), (uint32_t)in.size()) || !ktx2.start_transcoding()) return 1;
    std::vector<unsigned char> rgba(ktx2.get_width() * ktx2.get_height() * 4);
    if (!ktx2.transcode_image_level(0, 0, 0, rgba.data(), ktx2.get_width() * ktx2.get_height(),
                                    basist::transcoder_texture_format::cTFRGBA32)) return 1;
    FILE *out = std::fopen(argv[2], "wb");
    std::fprintf(out, "%u %u\n", ktx2.get_width(), ktx2.get_height());
    std::fwrite(rgba.data(), 1, rgba.size(), out);
    return std::fclose(out) != 0;
}
CPP
gcc -O1 -c "$vendor/zstd/zstddeclib.c" -o "$work/zstd.o"
g++ -O1 -I"$vendor" "$work/reference.cpp" "$vendor/transcoder/basisu_transcoder.cpp" "$work/zstd.o" \
    -o "$work/reference" 2>/dev/null

# 36x20 RGBA8: colour gradients, a disc and an alpha ramp; the sides are not multiples of the 4x4 blocks.
mkdir -p "$out"
cat >"$work/png.py" <<'PY'
import struct, sys, zlib
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
def write_png(path, w, h, rgba):
    rows = b"".join(b"\0" + rgba[y * w * 4:(y + 1) * w * 4] for y in range(h))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)
if sys.argv[1] == "source":
    w, h = 36, 20
    rgba = bytearray()
    for y in range(h):
        for x in range(w):
            disc = (x - 24) ** 2 + (y - 9) ** 2 < 36
            r, g, b = (250, 240, 40) if disc else (x * 7, y * 12, 255 - x * 5)
            rgba += bytes([r, g, b, 255 if x < 28 else 255 - (x - 27) * 25])
    write_png(sys.argv[2], w, h, bytes(rgba))
else:  # "raw": the reference program's "W H\n" + RGBA8 bytes
    data = open(sys.argv[2], "rb").read()
    header, rgba = data.split(b"\n", 1)
    w, h = map(int, header.split())
    write_png(sys.argv[3], w, h, rgba)
PY
python3 "$work/png.py" source "$out/source.png"

cd "$work"
"$basisu" -ktx2 -q 128 -comp_level 2 "$out/source.png" -output_file "$out/etc1s.ktx2" >/dev/null
"$basisu" -ktx2 -uastc -ktx2_zstandard_level 9 "$out/source.png" -output_file "$out/uastc.ktx2" >/dev/null
for kind in etc1s uastc; do
    "$work/reference" "$out/$kind.ktx2" "$work/$kind.raw"
    python3 "$work/png.py" raw "$work/$kind.raw" "$out/$kind.reference.png"
done
ls -l "$out"
