"""Pantograph presets and loading by name or parameter-file path."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..core.errors import ParameterError
from ..core.params import Table, load_toml
from ..core.registry import Registry
from .base import PantographModel, PantographOptions

DATA_DIR = Path(__file__).resolve().parent / "data"

#: preset name -> parameter file in ``data/``
PRESETS = Registry("pantograph preset", "model")
for _name in ("dsa380-rigid", "dsa380-flexible", "dsa380-lumped3", "en50318-2mass"):
    PRESETS.add(_name, f"{_name}.toml")


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


@dataclass(frozen=True)
class PresetDefaults:
    """What a preset or parameter file sets before any override: its ``[options]`` over the
    :class:`PantographOptions` defaults, and the working height of its default static start."""

    options: PantographOptions
    working_height: float


def _file_options(path: Path, data: dict) -> PantographOptions:
    return PantographOptions.from_table(Table(data.get("options", {}), str(path), "options"))


# each kind imports its own model on demand: a pantograph FMU loads the one model it runs
# (measured with the catenary factories in :mod:`pantocosim.catenary.models`)
def _chain():
    from .lumped import load_chain, read_chain

    return load_chain, lambda path: read_chain(path)[0].working_height


def _flexible():
    from .dsa380_flexible import load_dsa380_flexible, read_flexible

    return load_dsa380_flexible, lambda path: read_flexible(path)[0].rigid.working_height


def _rigid():
    from .dsa380 import load_dsa380, read_parameters

    return load_dsa380, lambda path: read_parameters(path)[0].working_height


#: the model kinds of parameter files, by the table that marks a file of the kind (looked
#: for in this order; "": none, the rigid DSA-380) -> factory of (loader, reader of the
#: working height)
MODEL_KINDS = Registry("pantograph model kind", "parameter file")
MODEL_KINDS.add("chain", _chain)
MODEL_KINDS.add("rigid_model", _flexible)
MODEL_KINDS.add("", _rigid)


def _model_kind(data: dict):
    """(loader, reader of the working height) of a parameter file, told by its tables."""
    return MODEL_KINDS[next(m for m in MODEL_KINDS if not m or m in data)]()


def preset_defaults(name_or_path: str | Path) -> PresetDefaults:
    """The defaults of a preset or parameter file, read and validated by the model's own
    readers without building the model (the pantograph FMU's parameter start values)."""
    path = preset_path(name_or_path)
    data = load_toml(path)
    _, working_height = _model_kind(data)
    return PresetDefaults(_file_options(path, data), working_height(path))


def load_pantograph(name_or_path: str | Path, options: PantographOptions | None = None,
                    **option_overrides) -> PantographModel:
    """Build a pantograph model from a preset name or a parameter file.

    ``option_overrides`` replace fields of the file's ``[options]`` (e.g. ``speed_kmh=300``)
    before the model is built, so its equilibrium and actuation account for them.
    """
    path = preset_path(name_or_path)
    data = load_toml(path)
    if options is None:
        options = _file_options(path, data)
    options = options.replaced(source=str(path), **option_overrides)
    load, _ = _model_kind(data)
    return load(path, options)
