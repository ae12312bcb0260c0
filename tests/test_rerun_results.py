"""Complete results are never lost to a rerun: a rerun stopped early (Ctrl-C) beside a
complete run writes ``OUT-stopped`` and says so; a staging folder left by a killed command is
removed by the next command writing the same ``--out``, one in use or kept on purpose is not."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pantocosim.master.cli import main
from pantocosim.master.interrupt import StopRequest, interrupted_at
from pantocosim.master.output_folder import OWNER, OutputFolder
from short_scenarios import LINEAR, THREE_SPANS



def files(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in folder.iterdir()}


@pytest.mark.slow
def test_a_rerun_stopped_by_ctrl_c_keeps_the_complete_results(tmp_path, capsys, monkeypatch):
    path = tmp_path / "s.toml"
    path.write_text(THREE_SPANS + LINEAR)
    out = tmp_path / "out"
    argv = ["run", str(path), "--quiet", "--no-plots", "--out", str(out)]
    assert main(argv) == 0
    complete = files(out)
    capsys.readouterr()

    def stop_at_step_20(self, t, step, n_steps):
        if step >= 20:
            raise interrupted_at(t, step, n_steps)

    monkeypatch.setattr(StopRequest, "check", stop_at_step_20)
    assert main(argv) == 130
    (line,) = [l for l in capsys.readouterr().err.splitlines() if l.strip()]
    assert "interrupted (Ctrl-C) at t = " in line and f"{out}-stopped" in line
    assert f"the complete results of an earlier run in {out} are kept" in line
    assert files(out) == complete
    stopped = json.loads((tmp_path / "out-stopped" / "summary.json").read_text())
    assert stopped["completed"] is False and stopped["stopped"]["steps"] == 20
    assert not list(tmp_path.glob("*.partial"))
    # a stopped run replaces a stopped one: OUT-stopped is written again, OUT stays
    assert main(argv) == 130
    assert files(out) == complete


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_a_staging_folder_of_a_killed_command_is_removed_by_the_next(tmp_path, sig):
    out = tmp_path / "out"
    child = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\n"
         "from pantocosim.master.output_folder import OutputFolder\n"
         f"f = OutputFolder({str(out)!r})\n(f.path / 'timeseries.csv').write_text('t')\n"
         "print(f.path, flush=True)\ntime.sleep(600)\n"], stdout=subprocess.PIPE, text=True)
    try:
        abandoned = Path(child.stdout.readline().strip())
        assert abandoned.is_dir()
        live = OutputFolder(out)              # the child's is in use: kept
        assert abandoned.is_dir()
    finally:
        child.send_signal(sig)
        child.wait(timeout=30)
    kept = OutputFolder(out)
    (kept.path / "summary.json").write_text("{}")
    kept._release()                            # as after a failed move: no lock file
    kept._kept = True
    OutputFolder(out).discard()
    assert not abandoned.exists()              # the killed command's: removed
    assert live.path.is_dir() and (live.path / OWNER).is_file()
    assert kept.path.is_dir()                  # kept on purpose, named in its error
    live.discard()
    assert not live.path.exists()


def test_a_ctrl_c_while_the_staging_folder_is_made_leaves_it_locked(tmp_path, monkeypatch):
    """A SIGINT between the staging folder and its lock is delivered after both exist, so
    the folder is never without its lock; the next command removes it once the lock is
    free."""
    import gc

    import pantocosim.master.output_folder as output_folder

    real_own = output_folder.own
    made = []

    def interrupted_own(path):
        made.append(path)
        os.kill(os.getpid(), signal.SIGINT)   # held back until the lock is taken
        return real_own(path)

    monkeypatch.setattr(output_folder, "own", interrupted_own)
    out = tmp_path / "out"
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # xdist ignores it
    try:
        with pytest.raises(KeyboardInterrupt) as stopped:
            OutputFolder(out)
    finally:
        signal.signal(signal.SIGINT, previous)
    (staging,) = made
    assert (staging / OWNER).is_file()
    del stopped
    gc.collect()                               # the interrupted command's lock goes
    monkeypatch.setattr(output_folder, "own", real_own)
    OutputFolder(out).discard()
    assert not staging.exists()
    assert not list(tmp_path.glob("*.partial"))
