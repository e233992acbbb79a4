"""What a model reference names, and the box that stands in for a model PyBullet cannot load.

Gazebo models are referenced as ``<package>://<path>`` (``example_simulation://models/box.sdf``),
``file://<path>``, ``model://<name>`` or plain paths. We look for the file in the scenario's
folder and its parent (a package's ``scenarios/`` folder sits beside its ``models/``), then in
pybullet_data. URDF files are loaded as they are. For anything else the first ``<box><size>`` of
an SDF (or URDF) file gives the stand-in box's size; without one, a :data:`DEFAULT_SIZE` box.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeAlias

from defusedxml import ElementTree
from defusedxml.common import DefusedXmlException

Size = tuple[float, float, float]
DEFAULT_SIZE: Size = (0.5, 0.5, 0.5)
MAX_MODEL_BYTES = 4 * 1024 * 1024


@dataclass
class UrdfModel:
    """A model spawned from its URDF file as it is; ``note`` says which file."""

    path: Path
    note: str


@dataclass
class BoxModel:
    """A box of ``size`` (metres, full lengths) standing in for a model; ``note`` says why."""

    size: Size
    static: bool
    note: str


#: how a model reference is spawned
ModelChoice: TypeAlias = UrdfModel | BoxModel


def reference_path(model: str) -> str:
    """The path part of a model reference (``pkg://models/box.sdf`` -> ``models/box.sdf``)."""
    if "://" in model:
        return model.split("://", 1)[1]
    return model


def locate(model: str, folders: Iterable[str | None], data_path: str) -> Path | None:
    """The file a model reference names: absolute, else in a scenario folder or its parent, else in pybullet_data."""
    relative = reference_path(model)
    candidate = Path(relative)
    if candidate.is_absolute():
        return candidate if candidate.is_file() else None
    for folder in folders:
        if not folder:
            continue
        for base in (Path(folder), Path(folder).parent):
            if (base / relative).is_file():
                return base / relative
    if (Path(data_path) / relative).is_file():
        return Path(data_path) / relative
    return None


def choose(model: str, folders: Iterable[str | None], data_path: str) -> ModelChoice:
    """Decide how to spawn ``model``; see the module docstring."""
    path = locate(model, folders, data_path)
    if path is None:
        return BoxModel(DEFAULT_SIZE, True, f"model '{model}' not found: a {_size_text(DEFAULT_SIZE)} box "
                        "stands in for it")
    if path.suffix == ".urdf":
        return UrdfModel(path, f"model '{model}': {path}")
    size, static = _box_of(path)
    if size is None:
        return BoxModel(DEFAULT_SIZE, static, f"model '{model}' ({path.name}) has no box geometry PyBullet "
                        f"can use here: a {_size_text(DEFAULT_SIZE)} box stands in for it")
    return BoxModel(size, static, f"model '{model}': a {_size_text(size)} box "
                    f"(its {path.suffix.lstrip('.').upper()} box geometry)")


def _box_of(path: Path) -> tuple[Size | None, bool]:
    """The size of the first box in an SDF/URDF file, and whether the model is static."""
    try:
        if path.stat().st_size > MAX_MODEL_BYTES:
            return None, True
        root = ElementTree.fromstring(path.read_bytes())
    except (OSError, ElementTree.ParseError, DefusedXmlException, ValueError):
        return None, True
    static = (root.findtext(".//static") or "true").strip().lower() in ("true", "1")
    for box in root.iter("box"):
        parts = (box.findtext("size") or box.get("size") or "").split()
        if len(parts) != 3:
            continue
        try:
            x, y, z = (float(v) for v in parts)
        except ValueError:
            continue
        if x > 0 and y > 0 and z > 0:
            return (x, y, z), static
    return None, static


def _size_text(size: Size) -> str:
    return "x".join(f"{v:g}" for v in size) + " m"
