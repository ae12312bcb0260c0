"""The floors of the package hold: dependencies point downwards, no import cycle, imports at
module top (docs/architecture.md, "Layers and imports").

Every module of ``fmus/`` (the package ``pantocosim``) and ``master/`` (``pantocosim.master``)
is parsed with ``ast``; the module graph counts every import, at module top or inside a
function, so that a cycle cannot hide behind a deferred import.
"""
from __future__ import annotations

import ast
import pathlib
import re
from collections import defaultdict

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]

# floor of each subpackage ("" is the package's own __init__: its version and the kernel
# cache); a module may import its own floor and the floors below.
# catenary, pantograph and multibody are siblings: none imports another.
FLOORS = {"": 0, "core": 0, "catenary": 1, "pantograph": 1, "multibody": 1,
          "interaction": 2, "fmi": 3, "master": 4}
SIBLING_IMPORTS: set[tuple[str, str]] = set()   # (from floor, to floor) documented exceptions

# intra-package imports allowed inside a function: (module, imported module) -> why.
# `pantocosim --help` imports every command module and the size guard's limits: its import
# time is 0.27-0.37 s with these deferred, 2.3 s with every command's body at module top.
DEFERRED = {
    ("pantocosim.catenary.size_guard", "pantocosim.catenary.mesh"):
        "--help shows MAX_DOFS; the mesh costs it 0.16 s",
    ("pantocosim.master.size_limits", "pantocosim.catenary.definition"):
        "--help shows the limits; the definition loader costs it 0.09 s",
    ("pantocosim.master.thirdparty.cofmupy_json", "pantocosim.master.thirdparty.common"):
        "the module also runs as CoFmuPy's child, in that tool's venv without pantocosim",
}
# a model registry's factory imports the one model it builds: the FMU slaves import in 0.46 s
# so, in 0.62 s with every catenary and pantograph model at module top
for _model in ("model", "linear", "modal"):
    DEFERRED["pantocosim.catenary.models", f"pantocosim.catenary.{_model}"] = "registry"
for _model in ("dsa380", "dsa380_flexible", "lumped"):
    DEFERRED["pantocosim.pantograph.presets", f"pantocosim.pantograph.{_model}"] = "registry"
#: packages whose functions other than ``add_parser`` may import what they run: a CLI
#: command's body (its module is imported by `pantocosim --help`, its body only when run)
DEFERRED_BODIES = ("pantocosim.master.commands.",)

# third-party modules whose import is deferred into the function that needs it: heavy to
# import (matplotlib, scipy.signal, dask/distributed, pyarrow: 0.3-2 s each, that
# `pantocosim --help`, an FMU's instantiate or a worker would pay for nothing) or optional
# (fmpy's FMU-side modules, the third-party masters' libraries); docs/architecture.md
HEAVY = {"matplotlib", "scipy.signal", "dask", "distributed", "fmpy", "libcosimpy", "ecospy",
         "pyarrow", "cofmupy"}
#: other deferred third-party imports: (module prefix, function) -> why
THIRD_PARTY_DEFERRED = {
    ("pantocosim.master.thirdparty.", "child"):
        "a third-party master's child process: numpy and scipy.sparse.linalg before any FMU "
        "loads (docs/pythonfmu-notes.md, B5); CoFmuPy's child runs in that tool's own venv",
    ("pantocosim.master.run.outcome", "finish"):
        "`resource` exists on POSIX only",
    ("pantocosim.master.stability", "departures"):
        "scipy.special (0.14 s) serves only a finished run's departures",
}


def module_name(path: pathlib.Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    parts = ["pantocosim", *parts[1:]] if parts[0] == "fmus" else ["pantocosim", *parts]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, pathlib.Path]:
    files = [*ROOT.glob("fmus/**/*.py"), *ROOT.glob("master/**/*.py")]
    return {module_name(p): p for p in files}


def deferred_imports(tree: ast.AST) -> dict[int, str]:
    """{id of an import node inside a function: the outermost function's name}."""
    found = {}
    for top in ast.walk(tree):
        if isinstance(top, ast.ClassDef) or top is tree:
            for f in ast.iter_child_nodes(top):
                if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    found.update({id(n): f.name for n in ast.walk(f)
                                  if isinstance(n, (ast.Import, ast.ImportFrom))})
    return found


def imports(name: str, path: pathlib.Path, known: dict) -> list[tuple[str, str | None, int]]:
    """(imported package module, the function it is imported in or None, line) of every
    import in a module."""
    tree = ast.parse(path.read_text())
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    deferred = deferred_imports(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            # a name that is a submodule depends on that module only (the package is being
            # initialised already); any other name depends on the module it comes from
            candidates = [f"{target}.{a.name}" if f"{target}.{a.name}" in known else target
                          for a in node.names]
        elif isinstance(node, ast.Import):
            candidates = [a.name for a in node.names]
        else:
            continue
        for c in dict.fromkeys(candidates):
            if c in known and c != name:
                found.append((c, deferred.get(id(node)), node.lineno))
    return found


def floor(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def graph() -> tuple[dict, dict]:
    known = modules()
    edges = defaultdict(set)
    lines = {}
    for name, path in known.items():
        for target, _, line in imports(name, path, known):
            edges[name].add(target)
            lines[name, target] = line
    return known, edges, lines


def strongly_connected(nodes, edges) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module (iterative)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = 0
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def against_floors(edges) -> list[tuple[str, str]]:
    """(importer, imported) of every upward or sideways import."""
    wrong = []
    for source in sorted(edges):
        for target in sorted(edges[source]):
            a, b = floor(source), floor(target)
            up = FLOORS[b] > FLOORS[a]
            sideways = (FLOORS[a] == FLOORS[b] and a != b and "" not in (a, b)
                        and (a, b) not in SIBLING_IMPORTS)
            if up or sideways:
                wrong.append((source, target))
    return wrong


@pytest.mark.parametrize("what", ["the floors", "master's rooms"])
def test_dependencies_point_downwards(what):
    check = against_floors if what == "the floors" else against_master_floors
    known, edges, lines = graph()
    wrong = [f"{known[a].relative_to(ROOT)}:{lines[a, b]} {a} -> {b}"
             for a, b in check(edges)]
    assert not wrong, f"imports against {what}:\n" + "\n".join(wrong)


def test_floor_check_finds_upward_and_sideways_imports():
    edges = {"pantocosim.core.x": {"pantocosim.catenary.mesh", "pantocosim.core.y"},
             "pantocosim.catenary.a": {"pantocosim.pantograph.b", "pantocosim.core.x"},
             "pantocosim.pantograph.b": {"pantocosim.interaction.coupled"},
             "pantocosim.fmi.c": {"pantocosim.interaction.coupled", "pantocosim"}}
    assert against_floors(edges) == [
        ("pantocosim.catenary.a", "pantocosim.pantograph.b"),
        ("pantocosim.core.x", "pantocosim.catenary.mesh"),
        ("pantocosim.pantograph.b", "pantocosim.interaction.coupled")]


def test_no_import_cycle():
    known, edges, _ = graph()
    cycles = strongly_connected(sorted(known), edges)
    assert not cycles, "import cycles:\n" + "\n".join(" <-> ".join(c) for c in cycles)


def test_cycle_finder_finds_a_cycle():
    edges = defaultdict(set, {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}})
    assert strongly_connected(["a", "b", "c", "d"], edges) == [["a", "b", "c"]]


def test_intra_package_imports_at_module_top():
    known = modules()
    wrong = []
    for name, path in sorted(known.items()):
        body = name.startswith(DEFERRED_BODIES)
        for target, inside, line in imports(name, path, known):
            if inside and (name, target) not in DEFERRED and not (body and inside != "add_parser"):
                wrong.append(f"{path.relative_to(ROOT)}:{line} {target}")
    assert not wrong, "package imports inside a function:\n" + "\n".join(wrong)


def test_deferred_allow_list_is_current():
    known = modules()
    used = {(name, target) for name, path in known.items()
            for target, inside, _ in imports(name, path, known) if inside}
    assert not set(DEFERRED) - used, set(DEFERRED) - used


def is_heavy(module: str) -> bool:
    return any(module == h or module.startswith(h + ".") for h in HEAVY)


def test_deferred_third_party_imports_are_heavy_ones():
    wrong = []
    for name, path in sorted(modules().items()):
        tree = ast.parse(path.read_text())
        nodes = {id(n): n for n in ast.walk(tree)}
        for node_id, function in deferred_imports(tree).items():
            n = nodes[node_id]
            if isinstance(n, ast.ImportFrom) and not n.level:
                if n.module.split(".")[0] == "pantocosim":
                    continue
                heavy = is_heavy(n.module) or all(is_heavy(f"{n.module}.{a.name}")
                                                  for a in n.names)
            elif isinstance(n, ast.Import):
                heavy = all(is_heavy(a.name) or a.name.split(".")[0] == "pantocosim"
                            for a in n.names)
            else:
                continue
            allowed = any(name.startswith(prefix) and function == f
                          for prefix, f in THIRD_PARTY_DEFERRED)
            if not heavy and not allowed:
                wrong.append(f"{path.relative_to(ROOT)}:{n.lineno} {ast.unparse(n)}")
    assert not wrong, "light imports inside a function:\n" + "\n".join(wrong)


# ----------------------------------------------------------------------------- master's rooms
#: master's rooms bottom to top (docs/architecture.md): a module imports its own floor and the
#: floors below; the longest matching room names a module's floor
MASTER_FLOORS = {
    "": 0, "scenario": 0, "output_folder": 0, "folder_lock": 0, "interrupt": 0,
    "expression": 0, "pacing": 0, "size_limits": 0, "stability": 0, "coupling": 0,
    "validation": 0, "regression": 0,
    "results": 1,                    # files, recorder, statistics, plots
    "run": 2,                        # a monolithic run: setup, checks, stepping, finish
    "fmu": 3,                        # the Python FMUs: build, check, embedding, runtime
    "ssp": 4,                        # the SSP file of a scenario's FMUs
    "fmu.dist": 5,                   # build-fmus' output: the FMUs with their SSP file
    "cosim": 5, "native": 5, "standalone": 5,
    "regress": 6, "campaign": 6, "benchmarks": 6, "thirdparty": 6,
    "commands": 7,                   # the CLI commands
    "cli": 8,                        # imports the commands by name (COMMANDS)
}


def master_floor(name: str) -> int:
    """The floor of a module of ``pantocosim.master`` (KeyError: a room not placed yet)."""
    parts = name.split(".")[2:]
    for room in [".".join(parts[:n]) for n in range(len(parts), 0, -1)] or [""]:
        if room in MASTER_FLOORS:
            return MASTER_FLOORS[room]
    raise KeyError(name)


def against_master_floors(edges) -> list[tuple[str, str]]:
    """(importer, imported) of every import of master that climbs to a room above, and every
    import of a CLI command from outside the commands."""
    wrong = []
    for source in sorted(edges):
        if not source.startswith("pantocosim.master"):
            continue
        for target in sorted(edges[source]):
            if not target.startswith("pantocosim.master"):
                continue
            commands = "pantocosim.master.commands"
            if (master_floor(target) > master_floor(source)
                    or target.startswith(commands) and not source.startswith(commands)):
                wrong.append((source, target))
    return wrong


def test_every_master_module_has_a_room():
    missing = []
    for name in modules():
        try:
            master_floor(name) if name.startswith("pantocosim.master") else None
        except KeyError:
            missing.append(name)
    assert not missing, "place these in MASTER_FLOORS:\n" + "\n".join(missing)
    assert master_floor("pantocosim.master") == 0
    with pytest.raises(KeyError):
        master_floor("pantocosim.master.new_room")


def test_master_floor_check_finds_climbs():
    edges = {"pantocosim.master.results.files": {"pantocosim.master.run.setup"},
             "pantocosim.master.fmu.dist": {"pantocosim.master.ssp"},
             "pantocosim.master.fmu.build": {"pantocosim.master.ssp"},
             "pantocosim.master.campaign.spec": {"pantocosim.master.commands.run"},
             "pantocosim.master.commands.run": {"pantocosim.master.commands.sweep",
                                                "pantocosim.master.run"}}
    assert against_master_floors(edges) == [
        ("pantocosim.master.campaign.spec", "pantocosim.master.commands.run"),
        ("pantocosim.master.fmu.build", "pantocosim.master.ssp"),
        ("pantocosim.master.results.files", "pantocosim.master.run.setup")]


# ----------------------------------------------------------------------------- C sources
#: the C99 standard headers
C_STANDARD = {"assert.h", "complex.h", "ctype.h", "errno.h", "fenv.h", "float.h",
              "inttypes.h", "iso646.h", "limits.h", "locale.h", "math.h", "setjmp.h",
              "signal.h", "stdarg.h", "stdbool.h", "stddef.h", "stdint.h", "stdio.h",
              "stdlib.h", "string.h", "tgmath.h", "time.h", "wchar.h", "wctype.h"}
#: the native FMUs' C sources (fmus/native) and the embedding library's (fmus/fmi/embedding)
NATIVE, EMBEDDING = ROOT / "fmus" / "native", ROOT / "fmus" / "fmi" / "embedding"
#: the C host that loads the FMUs (fmus/native/host), no part of an FMU: the platform headers
#: each of its files may include besides the C standard's, its own and the FMI function types
HOST = NATIVE / "host"
HOST_PLATFORM_HEADERS = {"host_loader.c": {"dlfcn.h", "windows.h"},   # loading a library
                         "host_loops.c": {"windows.h"}}                # the clock
HOST_FMI_HEADERS = {"../fmi2/fmi2FunctionTypes.h", "../fmi3/fmi3FunctionTypes.h"}


def includes(path: pathlib.Path) -> list[str]:
    """The header names a C file includes (``"x.h"`` and ``<x.h>`` alike)."""
    return re.findall(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', path.read_text(), re.M)


def c_files(folder: pathlib.Path) -> list[pathlib.Path]:
    return sorted(p for p in folder.rglob("*") if p.suffix in (".c", ".h"))


def test_native_fmu_sources_include_their_own_fmi_and_standard_headers_only():
    own = {p.name for p in NATIVE.glob("*.h")}
    fmi = {p.name for p in NATIVE.glob("fmi[23]/*.h")}
    files = [p for p in c_files(NATIVE) if p.parent == NATIVE]
    assert {"pcs_model.h", "pcs_data.c", "fmi2_front.c"} <= {p.name for p in files}
    assert {"fmi2Functions.h", "fmi3Functions.h"} <= fmi
    wrong = [f"{p.relative_to(ROOT)}: {h}" for p in files
             for h in includes(p) if h not in own | fmi | C_STANDARD]
    assert not wrong, "includes outside own, FMI and C standard headers:\n" + "\n".join(wrong)


def test_the_c_host_includes_the_fmi_types_and_its_platform_headers_only():
    """The host's files: the C standard's headers, the host's own, the FMI function types and
    the platform headers of HOST_PLATFORM_HEADERS; no FMU source includes a host file."""
    files = c_files(HOST)
    own = {p.name for p in files if p.suffix == ".h"}
    assert {"host.h", "host_main.c", "host_fmi2.c", "host_fmi3.c"} <= {p.name for p in files}
    wrong = [f"{p.relative_to(ROOT)}: {h}" for p in files for h in includes(p)
             if h not in C_STANDARD | own | HOST_FMI_HEADERS
             | HOST_PLATFORM_HEADERS.get(p.name, set())]
    wrong += [f"{p.relative_to(ROOT)}: {h}" for p in c_files(NATIVE) if p.parent != HOST
              for h in includes(p) if pathlib.PurePath(h).name in own]
    assert not wrong, "host includes outside its table:\n" + "\n".join(wrong)


def test_the_two_c_layers_never_include_each_other():
    layers = {NATIVE: c_files(NATIVE), EMBEDDING: c_files(EMBEDDING)}
    assert all(layers.values())
    wrong = []
    for here, other in ((NATIVE, EMBEDDING), (EMBEDDING, NATIVE)):
        theirs = {p.name for p in c_files(other)} - {p.name for p in c_files(here)}
        for p in layers[here]:
            wrong += [f"{p.relative_to(ROOT)}: {h}" for h in includes(p)
                      if pathlib.PurePath(h).name in theirs
                      or (".." in h and not (p.parent == HOST and h in HOST_FMI_HEADERS))]
    assert not wrong, "includes across the native FMUs and the embedding library:\n" + \
        "\n".join(wrong)


# ----------------------------------------------------------------------------- FMI libraries
#: the only modules of the package that import an FMI library: module -> the library
FMI_LIBRARY_IMPORTERS = {"pantocosim.fmi.fmi2_front": "pythonfmu",
                         "pantocosim.fmi.fmi3_front": "pythonfmu3"}


def fmi_library_imports(path: pathlib.Path) -> set[str]:
    """The FMI libraries (pythonfmu, pythonfmu3, fmpy) a module imports, anywhere in it."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                 [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level
                 else [])
        found |= {n.split(".")[0] for n in names} & {"pythonfmu", "pythonfmu3", "fmpy"}
    return found


def test_only_the_fronts_import_pythonfmu_and_nothing_imports_fmpy():
    found = {name: fmi_library_imports(path) for name, path in modules().items()
             if not name.startswith("pantocosim.master")}
    assert {n: libs for n, libs in found.items() if libs} == \
        {n: {lib} for n, lib in FMI_LIBRARY_IMPORTERS.items()}


def test_the_slaves_import_without_pythonfmu():
    import subprocess
    import sys

    code = ("import sys, pantocosim.fmi.catenary_slave, pantocosim.fmi.pantograph_slave, "
            "pantocosim.fmi.front; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('pythonfmu', 'pythonfmu3', 'fmpy')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"


def test_the_port_tables_import_no_slave():
    """The master, the SSP writer and the reference page read the port tables without the
    slave modules."""
    import subprocess
    import sys

    code = ("import sys, pantocosim.fmi.catenary_ports, pantocosim.fmi.pantograph_ports; "
            "print(sorted(m for m in sys.modules if m.endswith(('_slave', 'slave_base'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "[]"
