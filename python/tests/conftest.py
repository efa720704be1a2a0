"""Shared fixtures: one validated Renderer per test module, and a glTF scene of known layout written on the fly."""
import base64
import json
import os
import struct
import pathlib

import pytest

import strata

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def renderer():
    """A Renderer under the Khronos validation layer: a render raises on any message, and closing it (after the
    module's tests) raises on any message of the device's teardown."""
    try:
        r = strata.Renderer(validation=True, device=os.environ.get("STRATA_TEST_DEVICE"))
    except RuntimeError as e:
        pytest.fail(
            "the Python tests need the Khronos validation layer and a Vulkan device that traces rays; "
            f"run `sudo scripts/setup.sh` (Mesa's lavapipe works without a GPU). The error was: {e}"
        )
    yield r
    r.close()


def two_quads_gltf(path: pathlib.Path) -> pathlib.Path:
    """Two 0.5 m quads facing +Y, nodes "left" at x = -0.5 and "right" at x = +0.5 (one grey Lambertian material),
    under an orthographic camera 2 m above looking straight down with ymag = xmag = 1: at 64x64 pixels image x
    is world +x and image y world +z, 32 pixels to the metre. No light: strata adds its default key light."""
    h = 0.25
    positions = [(-h, 0.0, -h), (h, 0.0, -h), (h, 0.0, h), (-h, 0.0, h)]
    normals = [(0.0, 1.0, 0.0)] * 4
    indices = [0, 2, 1, 0, 3, 2]
    blob = b"".join(struct.pack("<3f", *p) for p in positions)
    blob += b"".join(struct.pack("<3f", *n) for n in normals)
    blob += struct.pack("<6H", *indices) + b"\0\0"
    s = 0.7071068
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "left", "mesh": 0, "translation": [-0.5, 0.0, 0.0]},
            {"name": "right", "mesh": 0, "translation": [0.5, 0.0, 0.0]},
            {"name": "camera", "camera": 0, "translation": [0.0, 2.0, 0.0], "rotation": [-s, 0.0, 0.0, s]},
        ],
        "cameras": [{"type": "orthographic", "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}}],
        "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-h, 0.0, -h], "max": [h, 0.0, h]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(doc))
    return path


@pytest.fixture
def quads(tmp_path):
    return two_quads_gltf(tmp_path / "quads.gltf")
