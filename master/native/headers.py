"""What the Python side of the native FMUs reads from their C headers in ``fmus/native/``,
where each number is defined once: value references (``<model>_vars.h``), limits
(``pcs_limits.h``), data-file kinds (``pcs_data.h``) and the fields of the data files'
``sizes`` and ``scalars`` sections (``pcs_layout.h``)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

import pantocosim

#: the C sources of the native models (installed with the package as pantocosim/native)
SOURCE_DIR = Path(pantocosim.__file__).resolve().parent / "native"


def header_numbers(header: str) -> dict[str, float]:
    """The ``#define NAME number`` lines of a header in :data:`SOURCE_DIR`: {NAME: number}."""
    text = (SOURCE_DIR / header).read_text()
    return {m.group(1): float(m.group(2)) for m in
            re.finditer(r"#define (\w+) (-?[0-9.]+(?:e[0-9]+)?)u?\b", text)}


def value_references(header: str) -> dict[str, int]:
    """The ``#define PREFIX_VR_NAME number`` lines of a model's header: {NAME: number} (the
    one place the value references are numbered)."""
    text = (SOURCE_DIR / header).read_text()
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"#define \w+?_VR_(\w+) (\d+)", text)}


def kind(name: str) -> int:
    """The data-file kind ``PCS_KIND_<name>`` (pcs_data.h)."""
    return int(header_numbers("pcs_data.h")[f"PCS_KIND_{name}"])


def fields(*prefixes: str) -> list[str]:
    """The fields of a section in position order: the ``#define <prefix>_NAME position``
    lines of pcs_layout.h for each prefix, in turn (positions 0, 1, ... without a gap)."""
    numbers = header_numbers("pcs_layout.h")
    out = []
    for prefix in prefixes:
        out += sorted((k[len(prefix) + 1:] for k in numbers if k.startswith(prefix + "_")),
                      key=lambda k, p=prefix: numbers[f"{p}_{k}"])
    positions = [numbers[f"{p}_{k}"] for p in prefixes
                 for k in out if f"{p}_{k}" in numbers]
    if positions != list(range(len(out))):
        raise ValueError(f"pcs_layout.h: the fields of {prefixes} are not numbered 0..n-1")
    return out


def pack(values: dict, dtype, *prefixes: str) -> np.ndarray:
    """The section of ``values`` {field: value}, every field of the prefixes and no other."""
    names = fields(*prefixes)
    if set(values) != set(names):
        raise ValueError(f"section fields {sorted(values)}, pcs_layout.h names {names}")
    return np.array([values[n] for n in names], dtype=dtype)


def unpack(section: np.ndarray, *prefixes: str) -> dict:
    """{field: value} of a section written by :func:`pack`."""
    names = fields(*prefixes)
    if len(section) != len(names):
        raise ValueError(f"a section of {len(section)} values, pcs_layout.h names {names}")
    return dict(zip(names, section.tolist()))
