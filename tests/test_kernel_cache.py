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
