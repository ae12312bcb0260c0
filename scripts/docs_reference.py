"""The reference pages of the documentation, generated from the code.

- ``reference/cli.md``: every ``pantocosim`` command from its argument parser;
- ``reference/scenario.md``, ``catenary.md``, ``pantograph.md``, ``sweep.md``,
  ``criteria.md``: every data-file field from the declarations the loaders read
  (:mod:`pantocosim.core.schema`);
- ``reference/fmu-ports.md``: the variables of every FMU from the tables the slaves register
  them from (:mod:`pantocosim.fmi.catenary_ports`, :mod:`pantocosim.fmi.pantograph_ports`).

The documentation build runs it through mkdocs-gen-files (``mkdocs.yml``); run alone it writes
the pages into a folder (``python scripts/docs_reference.py OUT``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _cell(text) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


# ---------------------------------------------------------------------------- CLI
def cli_page() -> str:
    import os

    from pantocosim.master.cli import build_parser

    os.environ["COLUMNS"] = "96"   # usage lines wrapped as on a 96-column terminal
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {c.dest: c.help for c in sub._choices_actions}
    out = ["# Command line\n\n",
           "Generated from the argument parsers of `pantocosim` (`pantocosim COMMAND --help` "
           "prints the same). A mistake in a flag or a file ends with one line naming it, "
           "the value and what is accepted, and exit status 2; Ctrl-C stops a run after the "
           "step in flight with exit status 130, its results so far kept.\n\n",
           "| command | what it does |\n|---|---|\n"]
    for name in sub.choices:
        out.append(f"| [`{name}`](#{name}) | {_cell(helps.get(name) or '')} |\n")
    for name, p in sub.choices.items():
        out.append(f"\n## {name}\n\n")
        if p.description:
            out.append(" ".join(p.description.split()) + "\n\n")
        usage = p.format_usage().removeprefix("usage: ").rstrip()
        out.append(f"```text\n{usage}\n```\n\n")
        rows = []
        for a in p._actions:
            if isinstance(a, argparse._HelpAction):
                continue
            flag = ", ".join(f"`{s}`" for s in a.option_strings) or f"`{a.dest}`"
            if a.option_strings and a.nargs != 0:
                flag += f" {a.metavar or a.dest.upper()}"
            choices = ", ".join(f"`{c}`" for c in a.choices) if a.choices else ""
            default = a.default
            if a.nargs == 0 or default in (None, argparse.SUPPRESS):
                default = ""
            elif isinstance(default, (list, tuple)):
                default = " ".join(map(str, default))
            rows.append(f"| {flag} | {_cell(a.help or '')} | {choices} | "
                        f"{_cell(default) and f'`{_cell(default)}`'} |\n")
        if rows:
            out.append("| argument | meaning | choices | default |\n|---|---|---|---|\n")
            out += rows
    return "".join(out)


# ---------------------------------------------------------------------------- formats
def _presets(names: list[str], where: str) -> str:
    return (f"\n**Presets** (`{where}`): " + ", ".join(f"`{n}`" for n in names) + ".\n")


def format_pages() -> dict[str, str]:
    from pantocosim.catenary import definition
    from pantocosim.core.schema import Format, markdown
    from pantocosim.master import scenario
    from pantocosim.master.campaign import assessment, spec
    from pantocosim.pantograph import base, dsa380, dsa380_flexible, lumped
    from pantocosim.pantograph.presets import PRESETS

    def sections(module, names, tag):
        out = []
        for n in names:
            sec = getattr(module, n)
            head = sec.title or ((f"`[{sec.path}]`" if sec.path else "Top level"))
            out.append(type(sec)(sec.path, sec.fields, sec.doc, sec.extra, sec.array,
                                 f"{tag}: {head}"))
        return out

    pantograph = Format("pantograph", "Pantograph parameter files", """\
A pantograph parameter file describes one model; its tables tell which: `[chain]` a
lumped-mass model, `rigid_model` a flexible-bar DSA-380, `[frame]` with `[bars]` the rigid
DSA-380. Every kind has the `[options]` table (defaults below), which a scenario's
`options` overrides. `pantocosim modal FILE` gives the modes of a file, `pantocosim pantograph
FILE` its time response, and a scenario's `model = "FILE"` runs it.
""", (*sections(base, ["OPTIONS", "RAMP"], "All kinds"),
      *sections(lumped, ["ROOT", "CHAIN"], "Lumped"),
      *sections(dsa380, ["ROOT", "FRAME", "BAR", "LINKS", "SPRINGS", "DAMPER", "VARIANT"],
                "Rigid DSA-380"),
      *sections(dsa380_flexible, ["ROOT", "FRAME", "MATERIAL", "SECTIONS", "MESH"],
                "Flexible DSA-380")))
    return {
        "scenario.md": markdown(scenario.FORMAT)
        + _presets(scenario.scenario_names(), "master/scenarios/"),
        "catenary.md": markdown(definition.FORMAT)
        + _presets(definition.preset_names(), "fmus/catenary/data/"),
        "pantograph.md": markdown(pantograph)
        + _presets(sorted(PRESETS), "fmus/pantograph/data/"),
        "sweep.md": markdown(spec.FORMAT) + _presets(spec.sweep_names(), "master/sweeps/"),
        "criteria.md": markdown(assessment.FORMAT) + _presets(
            sorted(p.stem for p in assessment.CRITERIA_DIR.glob("*.toml")),
            "master/campaign/"),
    }


# ---------------------------------------------------------------------------- FMU ports
def _start_cell(var, context) -> str:
    """An input's or parameter's start value as the FMU declares it; none for an output
    (what the FMU computes at initialisation) or a local."""
    if var.causality not in ("parameter", "input"):
        return ""
    start = var.start_value(context)
    if var.type == "Real":
        return f"{float(start):.6g}"
    if var.type == "Boolean":
        return str(bool(start)).lower()
    return _cell(start)


def _variables_table(variables, causalities: tuple, context=None) -> str:
    """The rows of the declared ``variables`` of ``causalities``: name, causality, type,
    unit, start, accepted values, meaning."""
    rows = [f"| `{v.name}` | {v.causality} | {v.type} | {v.unit or ''} | "
            f"{_start_cell(v, context)} | {_cell(v.range.text())} | {_cell(v.meaning)} |\n"
            for v in variables if v.causality in causalities]
    if not rows:
        return ""
    return ("| variable | causality | type | unit | start | accepted | meaning |\n"
            "|---|---|---|---|---|---|---|\n" + "".join(rows))


def fmu_page() -> str:
    from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY
    from pantocosim.fmi.pantograph_ports import VARIABLES as PANTOGRAPH
    from pantocosim.master.fmu.build import PANTOGRAPH_FMUS
    from pantocosim.pantograph.presets import preset_defaults

    out = ["# FMU ports and parameters\n\n",
           "Generated from the variables the FMUs declare (`pantocosim.fmi.pantograph_ports`, "
           "`pantocosim.fmi.catenary_ports`: the slaves register them, the master and the SSP "
           "writer take their port names from them; `pantocosim build-fmus` writes the FMUs "
           "into `dist/fmus/`). Every pantograph FMU has the same ports, so a model swap is a "
           "file swap; the catenary FMU has one set of ports per pantograph (`_1`, `_2`, ...). "
           "A parameter outside its accepted values stops the initialisation with a message "
           "naming it. The recipes for third-party masters are in "
           "[Third-party masters](../third-party.md).\n"]
    out.append("\n## Pantograph FMUs: ports\n\n"
               + _variables_table(PANTOGRAPH, ("input", "output")))
    for preset in PANTOGRAPH_FMUS:
        out.append(f"\n## Pantograph FMU `{preset}.fmu`: parameters\n\n"
                   + _variables_table(PANTOGRAPH, ("parameter",), preset_defaults(preset)))
    out.append("\n## Catenary FMU `catenary.fmu`\n\n### Ports\n\n"
               + _variables_table(CATENARY, ("input", "output"))
               + "\n### Parameters\n\n"
               + _variables_table(CATENARY, ("parameter",)))
    out.append(NATIVE_SECTION)
    return "".join(out)


NATIVE_SECTION = """
## Native FMUs (`pantocosim export-native`)

C FMUs with no Python inside, for hosts without Python (HIL rigs, real-time targets, FMI tools
on Windows): the same variables as the FMUs above, every parameter fixed at export (its
exported value is accepted, another is refused with `fmi2Error` naming it), the internal step
the scenario's `dt`, the start the one our master gives the Python FMU. Details, data file and
timings in [Native FMUs for a HIL rig](../tutorials/hil.md).

| FMU | what it models | limits |
|---|---|---|
| `catenary.fmu` | the linear catenary (constant matrices, exact dropper slackening) or the modal one; penalty contact inside with `contact_mode = 1` | the nonlinear catenary has no native form |
| `en50318-2mass.fmu`, `dsa380-lumped3.fmu` | a lumped chain with constant matrices | without collector friction or a one-way damper; static start |
| `dsa380-rigid.fmu` | the rigid DSA-380 (thesis 2.1.1), every option of the Python model, HHT-alpha with Newton on exact tangents | options and start fixed at export |
| `dsa380-flexible.fmu` | the flexible-bar DSA-380 (thesis 2.2), the same engine | options and start fixed at export |
"""


def pages() -> dict[str, str]:
    out = {"reference/cli.md": cli_page(), "reference/fmu-ports.md": fmu_page()}
    out.update({f"reference/{k}": v for k, v in format_pages().items()})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="folder to write the pages into")
    args = ap.parse_args(argv)
    for name, text in pages().items():
        path = args.out / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
elif __name__ == "<run_path>":   # run by mkdocs-gen-files during the documentation build
    import mkdocs_gen_files

    for _name, _text in pages().items():
        with mkdocs_gen_files.open(_name, "w") as _fh:
            _fh.write(_text)
