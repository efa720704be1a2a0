"""What opens its own Renderer: `strata.render(path, ...)` (load, render once, free the device) and the README's
example script. Kept apart from test_renderer.py's validated Renderer, which is closed by then."""
import importlib.util
import json

import numpy as np
import pytest

import strata
from conftest import REPO


def test_render_is_a_one_call_shortcut(quads):
    frame = strata.render(quads, size=(16, 16), spp=1, aovs=["depth"])
    assert frame["color"].shape == (16, 16, 4)
    # 8 pixels to the metre: the left quad's centre (x = -0.5) is pixel (4, 8), 2 m below the camera.
    assert frame["depth"][8, 4] == pytest.approx(2.0, abs=1e-3)
    assert frame["depth"][0, 0] == 0.0


def test_the_example_writes_a_labelled_dataset(tmp_path):
    spec = importlib.util.spec_from_file_location("labelled_dataset", REPO / "python/examples/labelled_dataset.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    out = tmp_path / "dataset"
    assert example.main([str(REPO / "scenes/cornell.toml"), str(out), "--views", "2", "--size", "32x24", "--spp", "2"]) == 0
    for view in range(2):
        data = np.load(out / f"view_{view:03d}.npz")
        assert data["color"].shape == (24, 32, 4) and data["instance"].dtype == np.uint32
        assert data["motion"].shape == (24, 32, 2)
        camera = json.loads((out / f"view_{view:03d}.json").read_text())
        assert np.asarray(camera["K"]).shape == (3, 3)
    assert not np.array_equal(np.load(out / "view_000.npz")["depth"], np.load(out / "view_001.npz")["depth"])
