"""Sweep files: loading, validation, expansion into cases, and the hash of each case's inputs.

A sweep file (examples in ``master/sweeps/``)::

    name = "en50318-speeds"
    description = "..."
    scenario = "en50318-300"      # base scenario: preset or TOML file (relative to this file)
    combine = "product"           # "product": every combination; "zip": i-th value of each axis
    criteria = "en50367"          # assessment criteria: preset or TOML file (optional)

    [run]                         # optional: how each case runs
    coupling = "monolithic"       # monolithic | explicit | gauss-seidel | implicit (or an axis)
    accelerator = "iqn-imvj"      # implicit coupling's interface acceleration
    force = false                 # run above 0.7 of the wave speed
    plots = false                 # each case's PNG plots

    [set]                         # optional: fixed changes to the base scenario (axis names)
    catenary_model = "linear"

    [axes]                        # one array of values per axis (names: campaign/axes.py)
    speed_kmh = [200.0, 250.0, 300.0]
    pantograph = ["en50318-2mass", "dsa380-lumped3"]
    catenary.contact_wire.tension = [18000.0, 20000.0, 22000.0]

Every case is validated on load as its own scenario and catenary would be; errors name the
sweep file, the axis and the value. A case is identified by the hash of its inputs (scenario,
catenary definition and pantograph parameter files as run, coupling), so a sweep run again
finds the cases it already ran.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

from pantocosim.catenary.definition import load_catenary, parse_definition
from pantocosim.core.errors import ParameterError
from pantocosim.core.params import Table, load_toml
from pantocosim.core.schema import OPTIONAL, Field, Format, Section
from pantocosim.master.campaign import axes as _axes_module
from pantocosim.master.campaign.assessment import load_criteria
from pantocosim.master.campaign.axes import COUPLINGS, CaseInputs, make_axis
from pantocosim.master.coupling import ACCELERATORS
from pantocosim.master.scenario import SCENARIO_DIR, parse_scenario, scenario_names
from pantocosim.pantograph.presets import preset_path

SWEEP_DIR = Path(__file__).resolve().parent.parent / "sweeps"
COMBINE = ("product", "zip")
DEFAULT_CRITERIA = "en50367"

#: the declared fields of a sweep file (the loader reads each through its declaration; the
#: reference page of the format is generated from them)
ROOT = Section("", [
    Field("name", "string", default=OPTIONAL, doc="name of the sweep (default: the file's "
          "name without -sweep)"),
    Field("description", "string", default="", doc="free text"),
    Field("scenario", "file", doc="base scenario: preset or TOML file (relative to this "
          "file)"),
    Field("combine", "string", default="product", choices=COMBINE,
          doc='"product": every combination of the axes; "zip": the i-th value of each axis',
          rule='"zip" needs axes of one length'),
    Field("criteria", "file", default=DEFAULT_CRITERIA, doc="assessment criteria: preset or "
          "TOML file (see the criteria format)"),
], extra=("run", "set", "axes"))
RUN = Section("run", [
    Field("coupling", "string", default="monolithic", choices=tuple(COUPLINGS),
          doc="how each case runs (may also be an axis)"),
    Field("accelerator", "string", default="iqn-imvj", choices=tuple(ACCELERATORS),
          doc="the implicit coupling's interface acceleration"),
    Field("force", "boolean", default=False, doc="run above 0.7 of the wave speed"),
    Field("plots", "boolean", default=False, doc="write each case's PNG plots"),
], doc="Optional table: how each case runs.")
RUN_DEFAULTS = {f.name: f.default for f in RUN.fields}
SET = Section("set", [], doc="Optional table: fixed changes to the base scenario, named as "
              "axes are (`catenary_model = \"linear\"`).")
AXES = Section("axes", [], doc="One array of values per axis (`speed_kmh = [200.0, 250.0]`); "
               "every case is validated as its own scenario and catenary would be. "
               + "\n\n".join(_axes_module.__doc__.split("\n\n")[1:3]))
FORMAT = Format("sweep", "Sweep files", """\
A sweep file describes a campaign: a base scenario, the axes to vary and the criteria to
assess; `pantocosim sweep FILE` runs it and `pantocosim report FOLDER` summarises it. Presets
live in `master/sweeps/`.
""", (ROOT, RUN, SET, AXES))


@dataclass
class Case:
    index: int                  # 0-based position in the sweep
    values: dict                # axis name -> value of this case
    scenario: dict              # the case's scenario table (file paths absolute)
    catenary: dict | None       # its own catenary definition table (None: the scenario's)
    run: dict                   # coupling, accelerator, force, plots
    key: str = ""               # hash of the inputs (case folder name)
    descriptors: dict = field(default_factory=dict)   # scenario, speed, catenary, model

    @property
    def label(self) -> str:
        return _label(self.values)


@dataclass
class Sweep:
    name: str
    description: str
    source: str
    scenario_path: Path
    combine: str
    axes: list                  # [(name, values)]
    settings: list              # [(name, value)] of [set]
    run: dict
    criteria: str
    cases: list
    duplicates: int = 0


def sweep_names() -> list[str]:
    return sorted(p.stem for p in SWEEP_DIR.glob("*.toml"))


def sweep_path(name_or_path: str | Path) -> Path:
    p = Path(name_or_path)
    if p.exists():
        return p
    cand = SWEEP_DIR / f"{name_or_path}.toml"
    if cand.exists():
        return cand
    raise ParameterError("sweep", str(name_or_path),
                         f"no such file (presets: {', '.join(sweep_names())})")


def load_sweep(name_or_path: str | Path) -> Sweep:
    """Load, validate and expand a sweep file."""
    path = sweep_path(name_or_path)
    source = str(path)
    t = Table(load_toml(path), source)
    ROOT.check_keys(t)
    base_path = _base_scenario(ROOT.read(t, "scenario"), path, source)
    run = _run_options(t.sub("run", required=False))
    combine = ROOT.read(t, "combine")
    criteria = ROOT.read(t, "criteria")

    try:
        load_criteria(criteria, base=path.parent)
    except ParameterError as exc:
        raise ParameterError("criteria", criteria, str(exc), source) from None
    settings = _flatten(t.sub("set", required=False).data)
    axes = _axes(t, settings, combine, source)
    base = _base_inputs(base_path, run)
    _check_case(base, source, "scenario", str(base_path), str(base_path))
    for name, value in settings:     # one at a time: errors name the entry
        _apply(base, name, value, f"set.{name}", source)
        _check_case(base, source, f"set.{name}", value,
                    f"{base.scenario['name']} with {name} = {_short(value)}")
    builder = _CaseBuilder(base, source, run)
    for name, values in axes:       # each value on its own first: errors name the axis
        for v in values:
            builder.build({name: v}, f"axes.{name}", v)
    cases, seen, dups = [], set(), 0
    for combo in _combinations(axes, combine):
        case = builder.build(combo, "case", combo)
        if case.key in seen:
            dups += 1
            continue
        seen.add(case.key)
        case.index = len(cases)
        cases.append(case)
    name = ROOT.read(t, "name")
    return Sweep(name=path.stem.replace("-sweep", "") if name is None else name,
                 description=ROOT.read(t, "description"), source=source,
                 scenario_path=base_path, combine=combine, axes=axes, settings=settings,
                 run=run, criteria=criteria, cases=cases, duplicates=dups)


# ---------------------------------------------------------------------------- parts
def _base_scenario(name: str, sweep_file: Path, source: str) -> Path:
    for cand in (sweep_file.parent / name, Path(name), SCENARIO_DIR / f"{name}.toml"):
        if cand.is_file():
            return cand.resolve()
    raise ParameterError("scenario", name, f"unknown scenario (presets: "
                         f"{', '.join(scenario_names())}) and no such file", source)


def _run_options(t: Table) -> dict:
    RUN.check_keys(t)
    return {f.name: f.read(t) for f in RUN.fields}


def _flatten(table: dict, prefix: str = "") -> list:
    """[(dotted name, leaf value)] of a (nested) TOML table."""
    out = []
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out += _flatten(value, name + ".")
        else:
            out.append((name, value))
    return out


def _axes(t: Table, settings: list, combine: str, source: str) -> list:
    axes = _flatten(t.sub("axes").data)
    if not axes:
        raise ParameterError("axes", {}, "needs at least one axis (name = [values])", source)
    fixed = {n for n, _ in settings}
    for name, values in axes:
        make_axis(name)
        if not isinstance(values, list) or not values:
            raise ParameterError(f"axes.{name}", values, "must be a non-empty array of values",
                                 source)
        if name in fixed:
            raise ParameterError(f"axes.{name}", values, "is also given in [set]", source)
        canon = [_canonical(v) for v in values]
        for i, c in enumerate(canon):
            if combine == "product" and c in canon[:i]:
                raise ParameterError(f"axes.{name}", values, f"repeats {values[i]!r}", source)
    if combine == "zip":
        n = {len(v) for _, v in axes}
        if len(n) > 1:
            raise ParameterError("combine", "zip", "needs axes of one length (have "
                                 + ", ".join(f"{k}: {len(v)}" for k, v in axes) + ")", source)
    return axes


def _combinations(axes: list, combine: str):
    names = [n for n, _ in axes]
    rows = (zip(*[v for _, v in axes]) if combine == "zip"
            else itertools.product(*[v for _, v in axes]))
    for row in rows:
        yield dict(zip(names, row))


def _base_inputs(path: Path, run: dict) -> CaseInputs:
    """The base scenario's table with every file path made absolute: catenary and pantograph
    files as ``pantocosim run`` reads them (relative to the scenario file), FMUs as the
    co-simulation finds them (master/cosim.py ``fmu_paths``)."""
    data = load_toml(path)
    sc = parse_scenario(copy.deepcopy(data), str(path), path.stem, base=path.parent)
    data.setdefault("name", path.stem)
    data["catenary"] = sc.catenary
    for p, spec in zip(data.get("pantographs", []), sc.pantographs):
        p["model"] = spec.model
        if isinstance(p, dict) and isinstance(p.get("fmu"), str):
            p["fmu"] = _absolute(p["fmu"], path.parent)
    return CaseInputs(scenario=data, run={k: run[k] for k in ("coupling", "accelerator")})


def _absolute(name: str, base: Path) -> str:
    """A file name made absolute if it names an existing file (a preset name stays)."""
    for cand in (Path(name), base / name):
        if cand.is_file():
            return str(cand.resolve())
    return name


def _apply(inputs: CaseInputs, name: str, value, field_name: str, source: str) -> None:
    axis = make_axis(name)
    if name.startswith("catenary.") and inputs.catenary is None:
        _load_catenary(inputs, field_name, source)
    try:
        axis.apply(inputs, value)
    except ValueError as exc:
        raise ParameterError(field_name, value, str(exc), source) from None


def _load_catenary(inputs: CaseInputs, field_name: str, source: str) -> None:
    name = inputs.scenario.get("catenary")
    try:
        d = load_catenary(str(name))
    except ParameterError as exc:
        raise ParameterError(field_name, name, f"catenary not loadable: {exc}", source) from None
    inputs.catenary = copy.deepcopy(d.raw)
    inputs.catenary_source = d.source


def _check_case(inputs: CaseInputs, source: str, field_name: str, value, where: str,
                checked: set | None = None) -> None:
    """Validate the case's scenario, catenary and pantograph files as a run would (files
    named in ``checked`` were found valid before)."""
    checked = set() if checked is None else checked
    try:
        parse_scenario(copy.deepcopy(inputs.scenario), where)
        if inputs.catenary is not None:
            parse_definition(copy.deepcopy(inputs.catenary), inputs.catenary_source)
        elif ("catenary", inputs.scenario["catenary"]) not in checked:
            load_catenary(str(inputs.scenario["catenary"]))
            checked.add(("catenary", inputs.scenario["catenary"]))
        for p in inputs.scenario["pantographs"]:
            if ("pantograph", p["model"]) not in checked:
                preset_path(p["model"])
                checked.add(("pantograph", p["model"]))
    except ParameterError as exc:
        raise ParameterError(field_name, value, f"{exc}", source) from None


class _CaseBuilder:
    """Cases from the base inputs; caches the files that enter the hash."""

    def __init__(self, base: CaseInputs, source: str, run: dict):
        self.base = base
        self.source = source
        self.run = run
        self.files: dict = {}
        self.checked: set = set()

    def build(self, values: dict, field_name: str, shown) -> Case:
        inputs = copy.deepcopy(self.base)
        for name, v in values.items():
            _apply(inputs, name, v, field_name if field_name != "case" else f"axes.{name}",
                   self.source)
        where = f"{self.base.scenario['name']} with {_label(values)}"
        _check_case(inputs, self.source, field_name, shown, where, self.checked)
        run = dict(self.run, **inputs.run)
        case = Case(index=-1, values=dict(values), scenario=inputs.scenario,
                    catenary=inputs.catenary, run=run)
        case.key = self.hash(case)
        sc = inputs.scenario
        case.descriptors = {
            "scenario": sc.get("name", ""), "speed_kmh": float(sc["speed_kmh"]),
            "catenary": Path(str(sc["catenary"])).stem,
            "catenary_model": sc.get("simulation", {}).get("catenary_model", "nonlinear"),
            "coupling": run["coupling"]}
        return case

    def _file(self, kind: str, name: str) -> dict:
        key = (kind, name)
        if key not in self.files:
            if kind == "catenary":
                self.files[key] = load_catenary(name).raw
            else:
                self.files[key] = load_toml(preset_path(name))
        return self.files[key]

    def hash(self, case: Case) -> str:
        """Hash of what the run depends on: the scenario with its catenary definition and
        pantograph parameter files in place of their names, and the coupling."""
        sc = copy.deepcopy(case.scenario)
        sc.pop("name", None)
        sc.pop("description", None)
        sc["catenary"] = (case.catenary if case.catenary is not None
                          else self._file("catenary", str(sc["catenary"])))
        for p in sc["pantographs"]:
            p["model"] = self._file("pantograph", p["model"])
        run = {"coupling": COUPLINGS[case.run["coupling"]]}
        if run["coupling"] == "implicit":
            run["accelerator"] = case.run["accelerator"]
        text = _canonical({"scenario": sc, "run": run})
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def _canonical(value) -> str:
    """JSON text that does not depend on key order or on 300 vs 300.0."""
    def norm(x):
        if isinstance(x, dict):
            return {str(k): norm(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [norm(v) for v in x]
        if isinstance(x, int) and not isinstance(x, bool):
            return float(x)
        return x
    return json.dumps(norm(value), sort_keys=True, separators=(",", ":"), default=str)


def _short(v) -> str:
    if isinstance(v, str):
        return Path(v).stem if ("/" in v or v.endswith(".toml")) else v
    return f"{v:g}" if isinstance(v, float) else str(v)


def _label(values: dict) -> str:
    return ", ".join(f"{k} = {_short(v)}" for k, v in values.items())
