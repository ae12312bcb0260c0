"""Every Sphinx-style cross-reference in the docstrings and comments of the package and in
docs/ (``:mod:``, ``:func:``, ``:class:``, ``:data:``, ``:meth:``, ``:attr:``, with the ``~``
and leading-``.`` forms) names an object that exists, so that a move cannot leave a reader
sent to a module that is gone.

A target is looked up as Sphinx would: an absolute ``pantocosim.`` path; a name of the class
the reference sits in (``:meth:`commit```), of the module itself (``:data:`BANDS```), or of
the module's package and its parents (``.model.CatenaryModel`` in
``pantocosim.catenary.models``); last, a leading ``.`` or a dotted name searched by suffix:
a module named by its last part (``.affine_hht.AffineHHT``) holding the rest.
"""

from __future__ import annotations

import ast
import importlib
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
#: stale references left where another change is rewriting the file: (file, role, target)
#: -> why; each must still be there (test below), so the entry goes when the file is fixed
KNOWN_STALE: dict = {}
ROLE = re.compile(r":(mod|func|class|data|meth|attr|exc|obj):`~?([^`<>]+?)`")


def module_of(path: pathlib.Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    parts = ["pantocosim", *parts[1:]] if parts[0] == "fmus" else ["pantocosim", *parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def sources() -> list[pathlib.Path]:
    return sorted([*ROOT.glob("fmus/**/*.py"), *ROOT.glob("master/**/*.py")])


def lookup(dotted: str) -> bool:
    """True if ``dotted`` is a module, or a module's attribute path (a class's annotated
    field counts)."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        for name in parts[n:]:
            if hasattr(obj, name):
                obj = getattr(obj, name)
            elif name in getattr(obj, "__annotations__", {}) or \
                    name in getattr(obj, "__dataclass_fields__", {}):
                obj = None
            else:
                return False
        return True
    return False


def candidates(target: str, module: str, is_package: bool, cls: str | None = None,
               known: tuple = ()) -> list[str]:
    """The dotted paths ``target`` may stand for in ``module``, inside the class ``cls``
    (module docstring); ``known``: every module name, for the search by suffix."""
    if target.startswith("pantocosim"):
        return [target]
    rel = target.lstrip(".")
    package = module if is_package else module.rpartition(".")[0]
    parents = package.split(".")
    out = [f"{module}.{cls}.{rel}"] if cls else []
    out += [f"{module}.{rel}"]
    out += [".".join(parents[:n] + [rel]) for n in range(len(parents), 0, -1)]
    head, _, rest = rel.partition(".")
    out += [f"{m}.{rest}" if rest else m for m in known if m.rpartition(".")[2] == head]
    return out


def classes_by_line(tree: ast.AST) -> dict[int, str]:
    """{line: the qualified name of the innermost class around it}."""
    found = {}

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            name = prefix
            if isinstance(child, ast.ClassDef):
                name = f"{prefix}.{child.name}" if prefix else child.name
                found.update({i: name for i in range(child.lineno, child.end_lineno + 1)})
            visit(child, name)

    visit(tree, "")
    return found


def instance_attributes(tree: ast.AST) -> dict[str, set[str]]:
    """{class name: the attributes its methods set on ``self``}."""
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            found[node.name] = {t.attr for t in ast.walk(node) if isinstance(t, ast.Attribute)
                                and isinstance(t.value, ast.Name) and t.value.id == "self"
                                and isinstance(t.ctx, ast.Store)}
    return found


def references() -> list[tuple[str, int, str, str, bool, str | None]]:
    """(file, line, role, target, module is a package, class around it) of every
    cross-reference."""
    found = []
    for path in sources():
        text = path.read_text()
        tree = ast.parse(text)
        classes, attributes = classes_by_line(tree), instance_attributes(tree)
        for i, line in enumerate(text.splitlines(), 1):
            for role, target in ROLE.findall(line):
                cls = classes.get(i)
                if role == "attr" and cls and target in attributes[cls.rpartition(".")[2]]:
                    continue          # set on self by a method of the class around it
                found.append((str(path.relative_to(ROOT)), i, role, target.strip(),
                              path.name == "__init__.py", cls))
    return found


def test_there_are_references_to_check():
    refs = references()
    assert len(refs) > 200
    assert {r[2] for r in refs} >= {"mod", "func", "class", "data", "meth"}


def test_every_cross_reference_resolves():
    wrong = []
    known = tuple(module_of(p) for p in sources())
    for file, line, role, target, is_package, cls in references():
        module = module_of(ROOT / file)
        if (file, role, target) in KNOWN_STALE:
            continue
        if not any(lookup(c) for c in candidates(target, module, is_package, cls, known)):
            wrong.append(f"{file}:{line} :{role}:`{target}`")
    assert not wrong, "cross-references to nothing:\n" + "\n".join(wrong)


def test_the_known_stale_ones_are_still_there():
    found = {(file, role, target) for file, _, role, target, _, _ in references()}
    assert set(KNOWN_STALE) <= found, set(KNOWN_STALE) - found


def test_the_lookup_fails_on_a_moved_name():
    assert lookup("pantocosim.core.stepper_contract.ClosedFormStep")
    assert lookup("pantocosim.core.stepper_contract.ClosedFormStep.delta_free")
    assert not lookup("pantocosim.core.stepping.make_stepper")
    assert not any(lookup(c) for c in candidates(".stepping.make_stepper",
                                                  "pantocosim.core.stepper_contract", False))


@pytest.mark.parametrize("page", sorted(p.name for p in (ROOT / "docs").rglob("*.md")))
def test_docs_pages_name_no_sphinx_role(page):
    """The pages are Markdown: a role would show as raw text."""
    text = next((ROOT / "docs").rglob(page)).read_text()
    assert not ROLE.search(text), ROLE.search(text).group(0)
