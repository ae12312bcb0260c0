"""Pantograph presets and loading by name or parameter-file path."""

from __future__ import annotations

from pathlib import Path

from ..core.errors import ParameterError
from ..core.params import Table, load_toml
from .base import PantographModel, PantographOptions

DATA_DIR = Path(__file__).resolve().parent / "data"

#: preset name -> parameter file in ``data/``
PRESETS = {
    "dsa380-rigid": "dsa380-rigid.toml",
    "dsa380-flexible": "dsa380-flexible.toml",
    "dsa380-lumped3": "dsa380-lumped3.toml",
    "en50318-2mass": "en50318-2mass.toml",
}


def preset_path(name_or_path: str | Path) -> Path:
    """File of a preset name, or the given path; unknown names raise a clear error."""
    key = str(name_or_path)
    if not key.strip():
        raise ParameterError("pantograph", key, f"empty name (presets: "
                             f"{', '.join(sorted(PRESETS))}, or a parameter file)")
    if key in PRESETS:
        return DATA_DIR / PRESETS[key]
    p = Path(key)
    if p.suffix == ".toml" or p.exists():
        if not p.exists():
            raise ParameterError("pantograph", key, "no such parameter file")
        return p
    raise ParameterError("pantograph", key,
                         f"unknown preset (known: {', '.join(sorted(PRESETS))}) and not a file")


def load_pantograph(name_or_path: str | Path, options: PantographOptions | None = None,
                    **option_overrides) -> PantographModel:
    """Build a pantograph model from a preset name or a parameter file.

    ``option_overrides`` replace fields of the file's ``[options]`` (e.g. ``speed_kmh=300``)
    before the model is built, so its equilibrium and actuation account for them.
    """
    path = preset_path(name_or_path)
    data = load_toml(path)
    if options is None:
        options = PantographOptions.from_table(Table(data.get("options", {}), str(path),
                                                     "options"))
    options = options.replaced(source=str(path), **option_overrides)
    if "chain" in data:
        from .lumped import load_chain

        return load_chain(path, options)
    if "rigid_model" in data:
        from .dsa380_flexible import load_dsa380_flexible

        return load_dsa380_flexible(path, options)
    from .dsa380 import load_dsa380

    return load_dsa380(path, options)
