"""strata: a headless Vulkan renderer (distributed ray tracing, validated on lavapipe), driven from Python.

    import strata
    renderer = strata.Renderer()
    scene = renderer.load("scenes/cornell.toml")
    frame = renderer.render(scene, size=(256, 256), spp=16, aovs=["depth", "instance"])
    frame["color"]     # (256, 256, 4) float32, linear radiance, alpha = coverage
    frame["depth"]     # (256, 256) float32, metres along the view axis
    frame["instance"]  # (256, 256) uint32, glTF node index + 1 (0: nothing)
    frame["camera"]    # dict: K, yfov, world_from_camera, ...

One Renderer keeps the device, the pipelines and each scene's uploads across renders; change a scene between
renders (node transforms, material factors, lights, environment) without reloading it. docs/outputs.md says what
every array holds, in units and axes; docs/python.md shows the whole API.
"""
from __future__ import annotations

import json
import os
from typing import Any, Dict, Iterable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _strata

__all__ = ["Renderer", "Scene", "render", "AOV_NAMES", "__version__"]

__version__: str = _strata.__version__
#: The AOV names `render(..., aovs=[...])` accepts (the command line's --aov names).
AOV_NAMES: Tuple[str, ...] = tuple(_strata.AOV_NAMES)

PathLike = Union[str, "os.PathLike[str]"]


class Scene:
    """A scene loaded once (``Renderer.load``) and changed between renders without a reload."""

    def __init__(self, native: "_strata.Scene") -> None:
        self._native = native

    @property
    def path(self) -> str:
        return str(self._native.path)

    @property
    def node_names(self) -> list:
        """The glTF nodes' names, in index order (a name or an index selects a node)."""
        return self._native.node_names

    @property
    def material_names(self) -> list:
        return self._native.material_names

    @property
    def warnings(self) -> list:
        """What strata did not read from the file (unsupported extensions, ...)."""
        return self._native.warnings

    def node_transform(self, node: Union[str, int]) -> np.ndarray:
        """The node's local transform (relative to its parent) as a 4x4 float32 array, rest pose."""
        return np.array(self._native.node_transform(node), dtype=np.float32)

    def set_node_transform(self, node: Union[str, int], matrix: Any) -> None:
        """Sets the node's local 4x4 transform (rows; last row 0 0 0 1); it moves in the next render."""
        m = np.asarray(matrix, dtype=np.float32)
        if m.shape != (4, 4):
            raise ValueError(f"a transform is a 4x4 matrix, not shape {m.shape}")
        self._native.set_node_transform(node, m.tolist())

    def set_material(
        self,
        material: Union[str, int],
        *,
        base_color: Optional[Sequence[float]] = None,
        metallic: Optional[float] = None,
        roughness: Optional[float] = None,
        emissive: Optional[Sequence[float]] = None,
    ) -> None:
        """Changes a material's factors (glTF's: linear RGBA base colour, metallic, roughness, emissive)."""
        self._native.set_material(
            material,
            base_color=None if base_color is None else [float(v) for v in base_color],
            metallic=metallic,
            roughness=roughness,
            emissive=None if emissive is None else [float(v) for v in emissive],
        )

    def set_environment(
        self, environment: Optional[PathLike], *, rotation: Optional[float] = None, intensity: Optional[float] = None
    ) -> None:
        """Lights the scene with "studio" (procedural) or an .hdr/.exr equirectangular image; None removes it."""
        self._native.set_environment(
            None if environment is None else os.fspath(environment), rotation=rotation, intensity=intensity
        )

    def add_directional_light(self, direction: Sequence[float], irradiance: Sequence[float]) -> None:
        """Adds a light travelling along `direction` with irradiance `irradiance` (linear RGB, W/m²)."""
        self._native.add_directional_light([float(v) for v in direction], [float(v) for v in irradiance])

    def set_camera(
        self,
        world_from_camera: Any,
        *,
        yfov: float = 45.0,
        znear: float = 0.01,
        zfar: Optional[float] = None,
        aperture: float = 0.0,
        focus: float = 1.0,
    ) -> None:
        """Sets a perspective camera: its 4x4 pose (glTF axes: it looks down its -Z with +Y up), the vertical field
        of view in degrees, clip planes in metres (zfar None: infinite), and a thin lens (aperture radius in
        metres, 0 a pinhole; focus distance in metres). A render's orbit or target still places its own."""
        m = np.asarray(world_from_camera, dtype=np.float32)
        if m.shape != (4, 4):
            raise ValueError(f"a camera pose is a 4x4 matrix, not shape {m.shape}")
        self._native.set_camera(m.tolist(), yfov=yfov, znear=znear, zfar=zfar, aperture=aperture, focus=focus)

    def clear_lights(self) -> None:
        """Removes the lights (emissive surfaces and the environment stay; with none, a default key light)."""
        self._native.clear_lights()

    def __repr__(self) -> str:
        return repr(self._native)


def _to_array(raw: Tuple[bytes, Sequence[int], str]) -> np.ndarray:
    data, shape, dtype = raw
    return np.frombuffer(data, dtype=np.dtype(dtype)).reshape(tuple(shape)).copy()


class Renderer:
    """A Vulkan device with strata's pipelines and the uploads of every live scene, kept across renders.

    validation: run under the Khronos validation layer; a render then raises RuntimeError on any message.
    device: a device name (substring) or index; None picks the first that traces rays.
    trace: "auto", "query" (ray queries) or "pipeline" (a ray-tracing pipeline).
    """

    def __init__(self, *, validation: bool = False, device: Optional[str] = None, trace: str = "auto") -> None:
        self._native = _strata.Renderer(validation=validation, device=device, trace=trace)

    @property
    def device(self) -> str:
        return self._native.device

    @property
    def device_bytes(self) -> int:
        """Bytes of device memory held now (the scenes' uploads)."""
        return self._native.device_bytes

    def load(
        self,
        path: PathLike,
        *,
        animation: Optional[Union[str, int]] = None,
        variant: Optional[str] = None,
        allow_any_uri: bool = False,
    ) -> Scene:
        """Loads a .gltf/.glb file, or a scene file (.toml) and the glTF it names."""
        return Scene(
            self._native.load(
                os.fspath(path),
                animation=None if animation is None else str(animation),
                variant=variant,
                allow_any_uri=allow_any_uri,
            )
        )

    def render(
        self,
        scene: Scene,
        *,
        size: Optional[Tuple[int, int]] = None,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        aovs: Iterable[str] = (),
        time: Optional[float] = None,
        fps: Optional[float] = None,
        shutter_angle: Optional[float] = None,
        orbit: Optional[Sequence[float]] = None,
        target: Optional[Sequence[float]] = None,
        yfov: Optional[float] = None,
        aperture: Optional[float] = None,
        focus: Optional[float] = None,
        environment: Optional[PathLike] = None,
        environment_rotation: Optional[float] = None,
        environment_intensity: Optional[float] = None,
        background: Optional[Union[str, Sequence[float]]] = None,
        indirect: Optional[bool] = None,
        bounces: Optional[int] = None,
        shading_samples: Optional[int] = None,
        sampler: Optional[str] = None,
        primary: Optional[str] = None,
        exposure: Optional[Union[float, str]] = None,
        tone_map: Optional[str] = None,
        denoise: bool = False,
    ) -> Dict[str, Any]:
        """Renders `scene` and returns a dict of numpy arrays (H rows, W columns), the same pixels
        `strata render` makes with the same options:

        "color": H×W×4 float32, linear radiance, alpha the coverage (denoised with denoise=True; then
        "noisy" holds the colour before). "display": H×W×4 uint8, the PNG's pixels (exposed, tone mapped, sRGB).
        One entry per AOV: "depth" H×W (metres), "normal"/"geometric-normal"/"position"/"albedo"/"emission"
        H×W×3, "material" H×W×4, "motion" H×W×2 (pixels to the next frame, x right, y down), "instance" and
        "semantic" H×W uint32. "camera": size, K, yfov (radians), world_from_camera, near/far, time, exposure.
        "stats": seconds, rays, the trace path. "warnings": what strata changed (a default light, ...).

        Options are the command line's (None: the scene file's, else strata's default): size=(W, H); orbit
        (theta, phi[, distance]) in degrees/metres and target (x, y, z) place the camera, yfov in degrees;
        time in seconds (the shutter opens then for shutter_angle/360 of 1/fps); exposure in stops or "auto";
        background "environment", "transparent" or (r, g, b); environment "studio" or an image file.
        Bad options raise ValueError; device failures RuntimeError. Ctrl-C stops between sample batches.
        """
        options = {
            "size": None if size is None else (int(size[0]), int(size[1])),
            "spp": spp,
            "seed": seed,
            "aovs": list(aovs),
            "time": time,
            "fps": fps,
            "shutter_angle": shutter_angle,
            "orbit": None if orbit is None else [float(v) for v in orbit],
            "target": None if target is None else tuple(float(v) for v in target),
            "yfov": yfov,
            "aperture": aperture,
            "focus": focus,
            "environment": None if environment is None else os.fspath(environment),
            "environment_rotation": environment_rotation,
            "environment_intensity": environment_intensity,
            "background": tuple(float(v) for v in background)
            if background is not None and not isinstance(background, str)
            else background,
            "indirect": indirect,
            "bounces": bounces,
            "shading_samples": shading_samples,
            "sampler": sampler,
            "primary": primary,
            "exposure": exposure,
            "tone_map": tone_map,
            "denoise": denoise,
        }
        raw = self._native.render(scene._native, options)
        out: Dict[str, Any] = {}
        for key, value in raw.items():
            if key == "camera":
                out[key] = json.loads(value)
            elif key in ("stats", "warnings"):
                out[key] = value
            else:
                out[key] = _to_array(value)
        return out

    def close(self) -> None:
        """Frees the device now; with validation, raises RuntimeError if the layer reported anything."""
        self._native.close()

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def render(path: PathLike, **options: Any) -> Dict[str, Any]:
    """Loads `path`, renders it once with `options` (see Renderer.render) and frees the device."""
    with Renderer() as renderer:
        return renderer.render(renderer.load(path), **options)
