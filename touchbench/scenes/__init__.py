"""Synthetic scenes: declarative descriptions of a sensor, a gesture
vocabulary, a population and recording conditions, turned into a
:class:`touchbench.datasets.TouchDataset` with the metadata a real reader
would produce.

>>> from touchbench.scenes import SCENES, generate_scene
>>> ds = generate_scene("tiny", seed=1)           # doctest: +SKIP

Shipped scenes live in ``touchbench/scenes/specs/*.yaml`` and are listed by
the :data:`SCENES` registry; any other YAML file may be given by path.
``load_dataset("scene:NAME")`` calls :func:`generate_scene`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..core.errors import DataError
from ..core.registry import Registry
from .generate import generate
from .loading import deep_merge, load_spec, parse_spec, read_yaml
from .spec import SceneSpec, is_subject_id

SPECS_DIR = Path(__file__).resolve().parent / "specs"

# load_dataset passes a dataset loader's keywords on; a scene has no use for them
_IGNORED = {"cache_dir", "data_dir", "refresh"}
_SUBSET = "\0gestures"  # marks gestures=[...]: a subset, not a merge
# shortcuts for the overrides people use most
_SHORTCUTS = {
    "subjects": ("population", "subjects"),
    "repetitions": ("protocol", "repetitions"),
    "lost": ("protocol", "lost"),
    "frames": ("protocol", "segmentation", "frames"),
}


def _load() -> None:
    for path in sorted(SPECS_DIR.glob("*.yaml")):
        raw, _ = read_yaml(path)
        name = raw.get("name", path.stem) if isinstance(raw, dict) else path.stem
        desc = str(raw.get("description", "")).strip().splitlines()[0] if isinstance(raw, dict) and raw.get("description") else ""
        SCENES.register(name, description=desc, path=str(path))(path)


SCENES: Registry = Registry("scene", loader=_load)


def scene_path(name_or_yaml: str | Path) -> Path:
    """The YAML file of a shipped scene name, or the path given."""
    s = str(name_or_yaml)
    if s in SCENES:
        return SCENES.get(s)
    p = Path(s)
    if p.suffix in (".yaml", ".yml") or p.exists():
        if not p.is_file():
            raise DataError("no such scene file", p)
        return p
    return SCENES.get(s)  # raises UnknownNameError with the nearest names


def _nest(path: tuple[str, ...], value: Any) -> dict[str, Any]:
    out: dict[str, Any] = {path[-1]: value}
    for k in reversed(path[:-1]):
        out = {k: out}
    return out


def overrides_to_dict(raw: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Keyword overrides as a nested dict to merge into the scene YAML.

    ``subjects``, ``repetitions``, ``lost``, ``frames`` are shortcuts;
    ``gestures=[...]`` keeps only those gestures (with their settings); any
    other key is a path with ``__`` or ``.`` between levels
    (``protocol__segmentation__pad_s=0.1``).
    """

    out: dict[str, Any] = {}
    for key, value in overrides.items():
        if key in _IGNORED:
            continue
        if key == "gestures":
            have = raw.get("gestures") or {}
            names = [value] if isinstance(value, str) else list(value)
            out[_SUBSET] = {g: have.get(g) for g in names}
            continue
        path = _SHORTCUTS.get(key) or tuple(key.replace(".", "__").split("__"))
        out = deep_merge(out, _nest(path, value))
    split = (raw.get("protocol") or {}).get("split") if isinstance(raw.get("protocol"), dict) else None
    if "subjects" in overrides and isinstance(split, dict) and "split" not in out.get("protocol", {}):
        # fewer people: keep the split of those that remain
        n = int(overrides["subjects"])
        kept = {k: [s for s in split.get(k, []) if is_subject_id(s, n)] for k in ("train", "test")}
        out = deep_merge(out, {"protocol": {"split": kept}})
    return out


def load_scene(name_or_yaml: str | Path, **overrides: Any) -> SceneSpec:
    """The validated scene, with ``overrides`` applied."""
    path = scene_path(name_or_yaml)
    if not overrides:
        return load_spec(path)
    raw, text = read_yaml(path)
    if not isinstance(raw, dict):
        raise DataError("a scene file holds a mapping", path)
    over = overrides_to_dict(raw, overrides)
    if _SUBSET in over:
        raw = {**raw, "gestures": over.pop(_SUBSET)}
    return parse_spec(deep_merge(raw, over), path, text, over)


def generate_scene(name_or_yaml: str | Path, seed: int | None = None, **overrides: Any):
    """Generate the dataset of a shipped scene (by name) or a YAML file.

    ``seed`` defaults to the scene's own; the same seed gives the same
    content hash. See :func:`overrides_to_dict` for ``overrides``.
    """

    spec = load_scene(name_or_yaml, **overrides)
    return generate(spec, seed=seed, source=scene_path(name_or_yaml))


__all__ = ["SCENES", "SPECS_DIR", "SceneSpec", "generate_scene", "load_scene", "scene_path"]
