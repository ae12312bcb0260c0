"""numba keeps the package's kernels by module and source content
(pantocosim.core.kernel_cache): a copy of the package in another folder (an FMU extracted
anew) loads them instead of compiling; a changed source compiles."""

import os
import subprocess
import sys

KERNEL = """from numba import njit


@njit(cache=True)
def triple(x):
    return {factor} * x
"""

PROBE = """import importlib.util
import sys

import pantocosim  # noqa: F401 - installs the locator

spec = importlib.util.spec_from_file_location("pantocosim.kernel_probe", sys.argv[1])
module = importlib.util.module_from_spec(spec)
sys.modules[spec.name] = module
spec.loader.exec_module(module)
print(module.triple(2.0), sum(module.triple.stats.cache_hits.values()))
"""


def run_copy(tmp_path, folder: str, factor: float):
    source = tmp_path / folder / "kernel_probe.py"
    source.parent.mkdir()
    source.write_text(KERNEL.format(factor=factor))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    out = subprocess.run([sys.executable, "-c", PROBE, str(source)], env=env, text=True,
                         capture_output=True, timeout=300, check=True).stdout.split()
    return float(out[0]), int(out[1])


def test_a_copy_in_another_folder_loads_the_kernel(tmp_path):
    assert run_copy(tmp_path, "first", 3.0) == (6.0, 0)        # compiled and kept
    assert run_copy(tmp_path, "second", 3.0) == (6.0, 1)       # another folder: loaded
    assert run_copy(tmp_path, "changed", 4.0) == (8.0, 0)      # another source: compiled
    kept = list((tmp_path / "cache" / "pantocosim" / "numba").iterdir())
    assert sorted(p.name.split("-")[0] for p in kept) == ["pantocosim.kernel_probe"] * 2


def probe(tmp_path, folder: str, cache_home):
    """Run the probe kernel copied in ``folder`` with the user cache at ``cache_home``."""
    source = tmp_path / folder / "kernel_probe.py"
    if not source.exists():
        source.parent.mkdir()
        source.write_text(KERNEL.format(factor=3.0))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(cache_home)
    return subprocess.run([sys.executable, "-c", PROBE, str(source)], env=env, text=True,
                          capture_output=True, timeout=300)


def warning_lines(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.strip()]


def test_a_damaged_kernel_entry_is_compiled_again_with_one_warning(tmp_path):
    cache = tmp_path / "cache"
    assert probe(tmp_path, "first", cache).returncode == 0
    kept = list((cache / "pantocosim" / "numba").rglob("*.nb[ic]"))
    assert sorted(p.suffix for p in kept) == [".nbc", ".nbi"]
    for damage in ("truncated", "garbage"):
        for entry in kept:
            data = entry.read_bytes() if entry.exists() else b"x" * 64
            entry.write_bytes(data[: len(data) // 3] if damage == "truncated"
                              else b"\x80\x05garbage" + data[::-1])
        done = probe(tmp_path, "first", cache)
        assert done.returncode == 0, done.stderr
        assert done.stdout.split() == ["6.0", "0"]                 # compiled, right result
        [line] = warning_lines(done.stderr)
        assert line.startswith("pantocosim: warning: cache ") and ".nbi" in line, line
        again = probe(tmp_path, "first", cache)                     # rewritten: loaded
        assert again.stdout.split() == ["6.0", "1"] and again.stderr == "", again.stderr


def test_a_file_where_the_kernel_folder_should_be(tmp_path):
    cache = tmp_path / "cache"
    (cache / "pantocosim").mkdir(parents=True)
    (cache / "pantocosim" / "numba").write_text("not a folder")
    done = probe(tmp_path, "first", cache)
    assert done.returncode == 0 and done.stdout.split()[0] == "6.0", done.stderr
    [line] = warning_lines(done.stderr)
    assert "numba" in line and "NUMBA_CACHE_DIR" in line, line


def test_a_file_where_the_cache_root_should_be(tmp_path):
    cache = tmp_path / "cache"
    cache.mkdir()
    (cache / "pantocosim").write_text("not a folder")
    done = probe(tmp_path, "first", cache)
    assert done.returncode == 0 and done.stdout.split()[0] == "6.0", done.stderr
    assert len(warning_lines(done.stderr)) == 1, done.stderr


def test_the_last_resort_folder_is_private_and_writable():
    """Where every other folder fails, a package kernel is kept in a temporary folder of the
    process (removed at exit); functions of other packages are left to numba."""
    import tempfile
    from pathlib import Path

    from pantocosim.core import kernel_cache

    locator = kernel_cache.ScratchCacheLocator.from_function(kernel_cache.root,
                                                             kernel_cache.__file__)
    folder = Path(locator.get_cache_path())
    assert folder.is_dir() and folder.parent == Path(tempfile.gettempdir())
    locator.ensure_cache_path()
    assert kernel_cache.ScratchCacheLocator.from_function(tempfile.mkdtemp,
                                                          tempfile.__file__) is None
    assert kernel_cache.ScratchCacheLocator in kernel_cache.caching.CacheImpl._locator_classes


TWO_KERNELS = """from numba import njit


@njit(cache=True)
def triple(x):
    return 3.0 * x


@njit(cache=True)
def other(x):
    return 5.0 * x
"""


def test_a_foreign_kernel_entry_is_not_trusted(tmp_path):
    """Another function's machine code under a kernel's name is compiled again, never run."""
    cache = tmp_path / "cache"
    source = tmp_path / "first" / "kernel_probe.py"
    source.parent.mkdir()
    source.write_text(TWO_KERNELS)
    code = PROBE.replace("print(", "module.other(1.0)\nprint(")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(cache)

    def run():
        return subprocess.run([sys.executable, "-c", code, str(source)], env=env, text=True,
                              capture_output=True, timeout=300)
    assert run().stdout.split() == ["6.0", "0"]
    [mine] = (cache / "pantocosim" / "numba").rglob("*triple*.nbc")
    [theirs] = (cache / "pantocosim" / "numba").rglob("*other*.nbc")
    mine.write_bytes(theirs.read_bytes())
    done = run()
    assert done.stdout.split() == ["6.0", "0"], done.stderr            # 3 x 2, not 5 x 2
    [line] = warning_lines(done.stderr)
    assert "holds other, not triple" in line, line
