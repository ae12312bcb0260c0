"""The set-up cache (pantocosim.core.disk_cache): a kept result is the computed one bit for
bit; any changed input misses; a corrupt entry is computed again with a warning; processes
that fill one entry at once leave one valid entry."""

import multiprocessing
import time

import numpy as np
import pytest
from waiting import later_mtime

from pantocosim.core import disk_cache


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("PANTOCOSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("PANTOCOSIM_NO_CACHE", raising=False)
    return tmp_path / "cache"


def two_span_line(speed_kmh=250.0):
    from pantocosim.catenary.definition import load_catenary, with_spans
    from pantocosim.catenary.model import CatenaryModel

    return CatenaryModel(with_spans(load_catenary("en50318"), 2), x0=[5.0],
                         speed=speed_kmh / 3.6)


def counting(fn):
    calls = []

    def compute():
        calls.append(1)
        return fn()
    return compute, calls


def test_the_moving_load_run_is_kept_bit_for_bit(cache):
    from pantocosim.catenary.operating_height import mean_dynamic_wire_height

    line = two_span_line()
    args = ([120.0], (40.0, 80.0), 2e-3, 1.3)
    cold = mean_dynamic_wire_height(line, *args)
    assert len(list(cache.glob("mean-wire-height-*.npz"))) == 1
    warm = mean_dynamic_wire_height(line, *args)
    assert warm.tobytes() == cold.tobytes()
    assert 5.0 < cold[0] < 5.8                      # a wire height, not a placeholder
    # another speed, step, force or window is another entry
    mean_dynamic_wire_height(two_span_line(200.0), *args)
    mean_dynamic_wire_height(line, [150.0], *args[1:])
    mean_dynamic_wire_height(line, args[0], args[1], 1e-3, args[3])
    assert len(list(cache.glob("mean-wire-height-*.npz"))) == 4
    # another catenary (a field of its definition) or another catenary model is another entry
    import dataclasses

    from pantocosim.catenary.linear import LinearCatenary
    from pantocosim.catenary.model import CatenaryModel

    d = line.definition
    tighter = dataclasses.replace(d, contact=dataclasses.replace(d.contact,
                                                                 tension=d.contact.tension + 1e3))
    other = mean_dynamic_wire_height(CatenaryModel(tighter, x0=[5.0], speed=250 / 3.6), *args)
    assert other[0] != cold[0]
    linear = mean_dynamic_wire_height(LinearCatenary(d, x0=[5.0], speed=250 / 3.6), *args)
    assert len(list(cache.glob("mean-wire-height-*.npz"))) == 6
    # the same linearisation, started from each model's own static state under the force
    assert linear[0] != cold[0] and linear[0] == pytest.approx(cold[0], abs=1e-4)


def test_every_input_and_the_package_stamp_change_the_key(monkeypatch):
    base = ("line", np.arange(4.0), 0.001, (1.0, 2.0))
    k = disk_cache.key("kind", base)
    changed = [("line2", np.arange(4.0), 0.001, (1.0, 2.0)),
               ("line", np.arange(4.0) + 1e-15, 0.001, (1.0, 2.0)),
               ("line", np.arange(4, dtype=np.float32), 0.001, (1.0, 2.0)),
               ("line", np.arange(4.0), 0.002, (1.0, 2.0)),
               ("line", np.arange(4.0), 0.001, (1.0, 2.5))]
    assert len({k} | {disk_cache.key("kind", p) for p in changed}) == 1 + len(changed)
    assert disk_cache.key("other", base) != k
    monkeypatch.setattr(disk_cache, "process_stamp", lambda: "another-build")
    assert disk_cache.key("kind", base) != k


def test_a_corrupt_entry_is_computed_again_with_a_warning(cache):
    compute, calls = counting(lambda: {"x": np.linspace(0.0, 1.0, 7)})
    first = disk_cache.cached("demo", (1,), compute)
    [entry] = cache.glob("demo-*.npz")
    entry.write_bytes(b"not an npz file")
    with pytest.warns(UserWarning, match="unusable"):
        again = disk_cache.cached("demo", (1,), compute)
    assert len(calls) == 2 and again["x"].tobytes() == first["x"].tobytes()
    assert disk_cache.cached("demo", (1,), compute)["x"].tobytes() == first["x"].tobytes()
    assert len(calls) == 2                           # the rewritten entry is used


def test_an_entry_of_another_key_is_not_trusted(cache):
    compute, calls = counting(lambda: {"x": np.ones(3)})
    disk_cache.cached("demo", (1,), compute)
    [entry] = cache.glob("demo-*.npz")
    other = cache / "elsewhere.npz"
    np.savez(other, __key__=np.array("0" * 64), x=np.zeros(3))
    other.replace(entry)                             # a foreign file under this entry's name
    with pytest.warns(UserWarning, match="stored key"):
        assert disk_cache.cached("demo", (1,), compute)["x"].tolist() == [1.0, 1.0, 1.0]


def test_no_cache_and_the_size_limit(cache, monkeypatch):
    compute, calls = counting(lambda: {"x": np.zeros(200_000)})   # 1.6 MB an entry
    monkeypatch.setenv("PANTOCOSIM_NO_CACHE", "1")
    disk_cache.cached("big", (0,), compute)
    assert not cache.exists() and len(calls) == 1
    monkeypatch.delenv("PANTOCOSIM_NO_CACHE")
    monkeypatch.setenv("PANTOCOSIM_CACHE_MB", "4")
    for i in range(5):
        disk_cache.cached("big", (i,), compute)
        later_mtime(max(cache.glob("big-*.npz"), key=lambda p: p.stat().st_mtime_ns))
    kept = sorted(cache.glob("big-*.npz"))
    assert len(kept) == 2                            # 3.2 MB of at most 4 MB: the newest two


def _fill(folder: str, barrier) -> None:
    import os

    os.environ["PANTOCOSIM_CACHE_DIR"] = folder
    barrier.wait()

    def slow():
        time.sleep(0.3)
        return {"x": np.arange(100_000, dtype=float)}
    disk_cache.cached("shared", ("same",), slow)


def test_processes_filling_one_entry_leave_one_valid_entry(cache):
    ctx = multiprocessing.get_context("spawn")
    barrier = ctx.Barrier(2)
    procs = [ctx.Process(target=_fill, args=(str(cache), barrier)) for _ in range(2)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(120)
    assert [p.exitcode for p in procs] == [0, 0]
    entries = list(cache.iterdir())
    assert len(entries) == 1 and entries[0].suffix == ".npz"    # no temporary file left
    compute, calls = counting(lambda: {"x": np.zeros(1)})
    kept = disk_cache.cached("shared", ("same",), compute)
    assert not calls and kept["x"].tobytes() == np.arange(100_000, dtype=float).tobytes()


from pantocosim.core.model import SecondOrderModel  # noqa: E402


class _NewtonLinearised(SecondOrderModel):
    """The linearised catenary of the moving-load run as a generic second-order model
    (M a + C v + K0 (q - q_static) = loads), for Newton-Raphson HHT steps."""

    def __init__(self, line):
        from pantocosim.catenary.operating_height import LinearisedCatenary

        self.lin, self.line, self.n_dofs = LinearisedCatenary(line), line, line.n_dofs

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        from pantocosim.core.model import Evaluation

        lin = self.lin
        ev = Evaluation(f_inertia=lin.M @ a, f_rest=lin._forces(t, q, v, inputs),
                        structure_key=0)
        if tangent:
            ev.mass, ev.damping, ev.stiffness = lin.M, lin.C, lin.K0
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        return self.line.effective_matrix(ev, c_a, c_v, c_f)

    def factorize(self, S):
        return self.line.factorize(S)


def test_the_closed_form_moving_load_run_is_the_newton_one():
    """The pre-run's closed-form HHT steps (pantocosim.core.affine_hht) solve the same
    linear equations as Newton-Raphson HHT (pantocosim.core.hht) on the model written out."""
    from pantocosim.catenary.operating_height import LinearisedCatenary, _moving_load_run
    from pantocosim.core.hht import DEFAULT_ALPHA, HHTIntegrator, HHTSettings

    line = two_span_line()
    F, window, dt, duration = np.array([150.0]), (40.0, 80.0), 2e-3, 1.3
    closed = _moving_load_run(line, LinearisedCatenary(line), F, window, dt, duration,
                              DEFAULT_ALPHA)
    model = _NewtonLinearised(line)
    integ = HHTIntegrator(model, HHTSettings(alpha=DEFAULT_ALPHA, rtol=1e-12))
    integ.initialize(0.0, line.static_state(F), np.zeros(line.n_dofs), F)
    heights = []
    for _ in range(int(np.ceil(duration / dt - 1e-9))):
        integ.step(dt, F)
        if window[0] <= line.positions(integ.t)[0] <= window[1]:
            heights.append(line.wire_height(integ.t, integ.q)[0])
    assert len(heights) > 100
    assert closed[0] == pytest.approx(np.mean(heights), abs=1e-9)   # m; the lift is ~5 cm
    assert abs(closed[0] - line.wire_height(0.0, line.q_static)[0]) > 1e-3


def test_the_modal_basis_is_kept_bit_for_bit(cache):
    from pantocosim.catenary.linear import LinearCatenary
    from pantocosim.catenary.modal import ModalCatenary

    lin = LinearCatenary(two_span_line().definition, x0=[5.0], speed=250 / 3.6)
    cold = ModalCatenary(linear=lin, cutoff_hz=40.0, keep_basis=True)
    assert len(list(cache.glob("modal-basis-*.npz"))) == 1
    warm = ModalCatenary(linear=lin, cutoff_hz=40.0, keep_basis=True)
    assert warm.Phi.tobytes() == cold.Phi.tobytes()
    assert warm.frequencies.tobytes() == cold.frequencies.tobytes()
    assert 0.5 < cold.frequencies[0] < 2.0 and cold.frequencies[-1] < 40.0    # Hz
    ModalCatenary(linear=lin, cutoff_hz=30.0)                       # another cutoff: missed
    assert len(list(cache.glob("modal-basis-*.npz"))) == 2


@pytest.mark.parametrize("value", ["", "relative/cache"])
def test_an_empty_or_relative_xdg_cache_home_means_the_home_cache(value, monkeypatch, tmp_path):
    """(XDG base directories: a relative path is ignored) every cache of the package is then
    under ~/.cache/pantocosim, never relative to the working folder."""
    from pantocosim.core.user_cache import cache_root

    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.setenv("XDG_CACHE_HOME", value)
    monkeypatch.delenv("PANTOCOSIM_CACHE_DIR", raising=False)
    assert cache_root() == tmp_path / ".cache" / "pantocosim"
    assert disk_cache.folder() == tmp_path / ".cache" / "pantocosim" / "setup"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert disk_cache.folder() == tmp_path / "xdg" / "pantocosim" / "setup"


@pytest.fixture
def fresh_warnings(monkeypatch):
    from pantocosim.core import user_cache

    monkeypatch.setattr(user_cache, "_warned", set())


def test_a_file_where_the_cache_folder_should_be(cache, fresh_warnings):
    cache.write_text("not a folder")
    compute, calls = counting(lambda: {"x": np.ones(3)})
    with pytest.warns(UserWarning, match="a file where the cache folder should be") as seen:
        for _ in range(2):
            assert disk_cache.cached("demo", (1,), compute)["x"].tolist() == [1.0] * 3
    assert len(calls) == 2 and len(seen) == 1 and cache.read_text() == "not a folder"
    assert str(cache) in str(seen[0].message)


def test_a_read_only_or_full_cache_runs_without_it(cache, fresh_warnings, monkeypatch):
    import errno
    import os

    compute, calls = counting(lambda: {"x": np.ones(3)})
    disk_cache.cached("kept", (1,), compute)                     # one entry already there

    def refuse(*args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))
    for name in ("savez",):
        monkeypatch.setattr(disk_cache.np, name, refuse)
    monkeypatch.setattr(disk_cache.Path, "unlink", refuse)
    monkeypatch.setattr(disk_cache.os, "utime", refuse)
    with pytest.warns(UserWarning, match="Read-only file system") as seen:
        for i in range(3):
            assert disk_cache.cached("demo", (i,), compute)["x"].tolist() == [1.0] * 3
    assert len(seen) == 1 and str(cache) in str(seen[0].message)
    assert disk_cache.cached("kept", (1,), compute)["x"].tolist() == [1.0] * 3   # still read
    assert len(calls) == 4


@pytest.mark.parametrize("value", ["lots", "-5", "nan", "12MB"])
def test_a_bad_size_limit_is_one_line_naming_the_variable(cache, monkeypatch, value):
    from pantocosim.core.errors import ParameterError

    monkeypatch.setenv("PANTOCOSIM_CACHE_MB", value)
    with pytest.raises(ParameterError, match=f"PANTOCOSIM_CACHE_MB = '{value}'") as refused:
        disk_cache.cached("demo", (1,), lambda: {"x": np.ones(3)})
    assert "\n" not in str(refused.value)
