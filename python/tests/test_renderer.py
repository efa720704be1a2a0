"""The Python package (issue 33): arrays of the right shapes and types, repeatable renders, scenes changed without
a reload, labels and K that follow the layout, the command line's pixels, errors as ValueError/RuntimeError, the
GIL released while rendering, and flat memory over 1,000 renders in one Renderer."""
import os
import pathlib
import struct
import subprocess
import threading
import zlib

import numpy as np
import pytest

import strata
from conftest import REPO

SIZE = 64
PIXELS_PER_METRE = 32


def columns_of(labels, label):
    """The image columns where the middle row shows `label`."""
    return np.flatnonzero(labels[SIZE // 2] == label).tolist()


def test_arrays_have_the_documented_shapes_and_types(renderer):
    scene = renderer.load(REPO / "scenes" / "cornell.toml")
    frame = renderer.render(scene, size=(48, 32), spp=2, aovs=list(strata.AOV_NAMES))
    assert frame["color"].shape == (32, 48, 4) and frame["color"].dtype == np.float32
    assert frame["display"].shape == (32, 48, 4) and frame["display"].dtype == np.uint8
    shapes = {"depth": (32, 48), "height": (32, 48), "instance": (32, 48), "semantic": (32, 48), "motion": (32, 48, 2),
              "normal": (32, 48, 3), "geometric-normal": (32, 48, 3), "albedo": (32, 48, 3), "position": (32, 48, 3),
              "emission": (32, 48, 3), "material": (32, 48, 4)}
    assert set(shapes) == set(strata.AOV_NAMES)
    for name, shape in shapes.items():
        assert frame[name].shape == shape, name
        assert frame[name].dtype == (np.uint32 if name in ("instance", "semantic") else np.float32), name
    camera = frame["camera"]
    assert (camera["width"], camera["height"]) == (48, 32)
    assert np.asarray(camera["K"]).shape == (3, 3)
    assert frame["stats"]["samples"] == 2
    # The box fills the middle of the frame; where a surface is seen its depth is positive, its normal a unit
    # vector and its instance label a node; elsewhere all three are 0.
    seen = frame["depth"] > 0
    assert seen[8:24, 16:32].all() and not seen.all()
    assert np.allclose(np.linalg.norm(frame["geometric-normal"][seen], axis=1), 1.0, atol=1e-3)
    assert (frame["instance"][seen] > 0).all() and (frame["instance"][~seen] == 0).all()


def test_the_same_render_twice_gives_the_same_arrays(renderer, quads):
    scene = renderer.load(quads)
    a = renderer.render(scene, size=(SIZE, SIZE), spp=4, aovs=["depth", "instance"])
    b = renderer.render(scene, size=(SIZE, SIZE), spp=4, aovs=["depth", "instance"])
    for key in ("color", "display", "depth", "instance"):
        assert np.array_equal(a[key], b[key]), key
    assert a["warnings"] and "default key light" in a["warnings"][0]


def test_a_moved_node_moves_without_a_reload(renderer, quads):
    scene = renderer.load(quads)
    right = scene.node_names.index("right")
    first = renderer.render(scene, size=(SIZE, SIZE), spp=1, aovs=["instance"])
    held = renderer.device_bytes
    before = columns_of(first["instance"], right + 1)
    assert len(before) == PIXELS_PER_METRE // 2, before
    moved = scene.node_transform("right")
    moved[0, 3] += 0.25
    scene.set_node_transform("right", moved)
    second = renderer.render(scene, size=(SIZE, SIZE), spp=1, aovs=["instance"])
    assert columns_of(second["instance"], right + 1) == [x + PIXELS_PER_METRE // 4 for x in before]
    assert renderer.device_bytes == held, "nothing was uploaded again"
    # The left quad stayed.
    left = scene.node_names.index("left")
    assert columns_of(second["instance"], left + 1) == columns_of(first["instance"], left + 1)


def test_k_reprojects_each_quad_centre_onto_its_label(renderer, quads):
    scene = renderer.load(quads)
    frame = renderer.render(scene, size=(80, 60), spp=1, aovs=["instance"], orbit=(30, 40))
    camera = frame["camera"]
    k = np.asarray(camera["K"])
    camera_from_world = np.asarray(camera["camera_from_world_opencv"])
    for name, x in (("left", -0.5), ("right", 0.5)):
        p = camera_from_world @ np.array([x, 0.0, 0.0, 1.0])
        u, v, w = k @ p[:3]
        px, py = int(u / w), int(v / w)
        assert frame["instance"][py, px] == scene.node_names.index(name) + 1, (name, px, py)


def test_a_camera_set_from_python_is_the_one_rendered(renderer, quads):
    scene = renderer.load(quads)
    eye = np.array([0.3, 1.5, 1.2])
    forward = -eye / np.linalg.norm(eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = right, up, -forward, eye
    scene.set_camera(pose, yfov=50)
    frame = renderer.render(scene, size=(64, 48), spp=1, aovs=["instance"])
    camera = frame["camera"]
    assert np.allclose(np.asarray(camera["world_from_camera"]), pose, atol=1e-6)
    assert camera["yfov"] == pytest.approx(np.radians(50))
    k, camera_from_world = np.asarray(camera["K"]), np.asarray(camera["camera_from_world_opencv"])
    for name, x in (("left", -0.5), ("right", 0.5)):
        u, v, w = k @ (camera_from_world @ np.array([x, 0.0, 0.0, 1.0]))[:3]
        assert frame["instance"][int(v / w), int(u / w)] == scene.node_names.index(name) + 1, name
    with pytest.raises(ValueError, match="yfov"):
        scene.set_camera(pose, yfov=200)


def read_png_rgba8(path):
    """An 8-bit RGBA, non-interlaced PNG's pixels (what strata writes), decoded with zlib alone."""
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert (depth, colour, interlace) == (8, 6, 0), header
    raw = zlib.decompress(idat)
    stride, bpp = width * 4, 4
    out = np.zeros((height, stride), dtype=np.uint8)
    prior = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, dtype=np.int32)
        for i in range(stride):
            a = cur[i - bpp] if i >= bpp else 0
            b = prior[i]
            c = prior[i - bpp] if i >= bpp else 0
            if kind == 0:
                pred = 0
            elif kind == 1:
                pred = a
            elif kind == 2:
                pred = b
            elif kind == 3:
                pred = (a + b) // 2
            else:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[i] = (line[i] + pred) & 0xFF
        out[y] = cur
        prior = cur
    return out.reshape(height, width, 4)


def strata_cli():
    """The command line `strata` binary: $STRATA_BIN, else the repository's release or debug build."""
    for candidate in (os.environ.get("STRATA_BIN"), REPO / "target/release/strata", REPO / "target/debug/strata"):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    pytest.fail("no strata binary: run `cargo build --release` (or set STRATA_BIN) before the Python tests")


def test_python_and_the_command_line_give_the_same_pixels(renderer, tmp_path):
    scene_path = REPO / "scenes" / "cornell.toml"
    png = tmp_path / "box.png"
    cli = subprocess.run(
        [strata_cli(), "render", str(scene_path), "--size", "40x30", "--spp", "4", "--orbit", "15,10",
         "--exposure", "auto", "-o", str(png), "--quiet"],
        capture_output=True, text=True,
    )
    assert cli.returncode == 0, cli.stderr
    scene = renderer.load(scene_path)
    frame = renderer.render(scene, size=(40, 30), spp=4, orbit=(15, 10), exposure="auto")
    assert np.array_equal(read_png_rgba8(png), frame["display"])


def test_a_frame_at_a_time_matches_the_command_lines_time(renderer, tmp_path):
    """--time t opens the shutter at t for half a frame at 24 fps; time=t does the same, to the byte."""
    scene_path = REPO / "scenes" / "motion.toml"
    png = tmp_path / "motion.png"
    cli = subprocess.run(
        [strata_cli(), "render", str(scene_path), "--size", "32x24", "--spp", "4", "--time", "0.5",
         "-o", str(png), "--quiet"],
        capture_output=True, text=True,
    )
    assert cli.returncode == 0, cli.stderr
    scene = renderer.load(scene_path)
    frame = renderer.render(scene, size=(32, 24), spp=4, time=0.5)
    assert frame["camera"]["time"] == 0.5
    assert np.array_equal(read_png_rgba8(png), frame["display"])
    still = renderer.render(scene, size=(32, 24), spp=4)
    assert not np.array_equal(still["display"], frame["display"]), "the scene moves between its shutter and t = 0.5"


def test_bad_input_is_a_value_error_that_names_the_problem(renderer, quads, tmp_path):
    with pytest.raises(ValueError, match="no/such/scene.gltf"):
        renderer.load("no/such/scene.gltf")
    broken = tmp_path / "broken.gltf"
    broken.write_text("{ not json")
    with pytest.raises(ValueError, match="broken.gltf"):
        renderer.load(broken)
    scene = renderer.load(quads)
    with pytest.raises(ValueError, match="unknown AOV \"colour\""):
        renderer.render(scene, size=(8, 8), spp=1, aovs=["colour"])
    with pytest.raises(ValueError, match="width 0"):
        renderer.render(scene, size=(0, 8), spp=1)
    with pytest.raises(ValueError, match="no node called \"middle\""):
        scene.set_node_transform("middle", np.eye(4))
    with pytest.raises(ValueError, match="4x4"):
        scene.set_node_transform("left", np.eye(3))
    with pytest.raises(ValueError, match="roughness"):
        scene.set_material("grey", roughness=2.0)
    with pytest.raises(ValueError, match="background"):
        renderer.render(scene, size=(8, 8), spp=1, background="sky")
    with pytest.raises(ValueError, match="needs an environment"):
        renderer.render(scene, size=(8, 8), spp=1, background="environment")


def test_the_gil_is_released_while_rendering(renderer, quads):
    scene = renderer.load(quads)
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(1)
            done.wait(0.005)

    ticker = threading.Thread(target=tick)
    ticker.start()
    try:
        before = len(ticks)
        renderer.render(scene, size=(128, 128), spp=16)
        during = len(ticks) - before
    finally:
        done.set()
        ticker.join()
    assert during >= 5, f"another Python thread ran only {during} times during the render"


def test_denoise_gives_the_denoised_and_the_noisy_colour_or_says_how_to_install_it(renderer):
    scene = renderer.load(REPO / "scenes" / "cornell.toml")
    required = os.environ.get("STRATA_REQUIRE_DENOISER") == "1"
    try:
        frame = renderer.render(scene, size=(32, 32), spp=2, denoise=True)
    except RuntimeError as e:
        assert not required, f"STRATA_REQUIRE_DENOISER=1 but denoising failed: {e}"
        assert "setup.sh --denoiser" in str(e)
        return
    assert frame["color"].shape == frame["noisy"].shape == (32, 32, 4)
    assert not np.array_equal(frame["color"], frame["noisy"])

