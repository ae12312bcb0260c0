"""One writer per output folder (master/folder_lock.py): a second sweep or build into the same
--out stops naming the holder (exit 2) or waits with --wait; a killed holder's lock is free."""

import json
import os
import signal
import subprocess
import sys
import threading

import pytest
from waiting import wait_until

from pantocosim.master.cli import main
from pantocosim.master.folder_lock import LOCK_NAME, FolderBusy, FolderLock, holder_of

SWEEP = """\
name = "locked"
scenario = "en50318-250"

[axes]
speed_kmh = [200.0, 250.0]
"""


def test_second_lock_names_the_holder(tmp_path):
    with FolderLock(tmp_path / "out"):
        holder = holder_of(tmp_path / "out")
        assert holder["pid"] == os.getpid() and holder["command"].startswith("pantocosim")
        with pytest.raises(FolderBusy) as err:
            with FolderLock(tmp_path / "out"):
                pass
        text = str(err.value)
        assert text.startswith(f"--out = '{tmp_path / 'out'}': pid {os.getpid()} on ")
        assert "is writing there; wait for it to end, run with --wait" in text
    with FolderLock(tmp_path / "out"):   # released: free again
        pass
    assert holder_of(tmp_path / "out")["pid"] == os.getpid()   # the last holder


def test_wait_takes_the_lock_when_the_holder_ends(tmp_path):
    got = threading.Event()
    messages = []

    def second():
        with FolderLock(tmp_path, wait=True, echo=messages.append):
            got.set()

    first = FolderLock(tmp_path).__enter__()
    t = threading.Thread(target=second)
    t.start()
    wait_until(lambda: messages, "the waiter finding the lock held", timeout=30.0)
    assert not got.is_set()
    assert messages[0].startswith(f"waiting for pid {os.getpid()} on ")
    first.__exit__(None, None, None)
    t.join()
    assert got.is_set()


def test_a_killed_holder_leaves_no_lock(tmp_path):
    code = ("import sys, time; from pantocosim.master.folder_lock import FolderLock\n"
            f"FolderLock({str(tmp_path)!r}).__enter__(); print('held', flush=True); "
            "time.sleep(600)")
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "held"
        with pytest.raises(FolderBusy, match=f"pid {child.pid} on "):
            with FolderLock(tmp_path):
                pass
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait()
    assert holder_of(tmp_path)["pid"] == child.pid   # what it wrote is still there ...
    with FolderLock(tmp_path):                       # ... but the lock is free
        assert holder_of(tmp_path)["pid"] == os.getpid()


def test_sweep_into_a_locked_folder_stops_with_one_line(tmp_path, capsys):
    sweep = tmp_path / "s-sweep.toml"
    sweep.write_text(SWEEP)
    out = tmp_path / "out"
    with FolderLock(out):
        assert main(["sweep", str(sweep), "--out", str(out), "--quiet"]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if l.strip()]
    assert len(err) == 1 and err[0].startswith(
        f"pantocosim sweep: error: --out = '{out}': pid {os.getpid()} on "), err
    assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME]   # nothing else written


def test_build_into_a_locked_folder_stops_with_one_line(tmp_path, capsys):
    out = tmp_path / "fmus"
    with FolderLock(out):
        assert main(["build-fmus", "--out", str(out), "--only", "catenary"]) == 2
    err = [l for l in capsys.readouterr().err.splitlines() if l.strip()]
    assert len(err) == 1 and "pantocosim build-fmus: error: --out = " in err[0] \
        and "is writing there" in err[0], err
    assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME]
