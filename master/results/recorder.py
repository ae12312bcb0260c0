"""Streams the time series of a run to a CSV file while keeping the columns the statistics need.

Each row is formatted as it comes (a few microseconds, the same every step: a paced loop sees
no periodic burst) into the file's buffer, which goes to disk every ``flush_every`` steps, so a
long run keeps what it has computed even if it stops with an error; the columns are also kept in memory (they are small
next to the model: a few floats per step). A write that fails (a full disk) raises
:class:`~pantocosim.core.errors.OutputError` naming the file; the recorder then stops writing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pantocosim.core.errors import OutputError
from pantocosim.master.output_folder import write_error, writing

#: rows the in-memory columns start with when the caller does not say (doubled when full)
INITIAL_ROWS = 1024


class Recorder:
    def __init__(self, path: Path | None, names: list[str], flush_every: int = 500,
                 rows: int = INITIAL_ROWS):
        """``rows``: the rows the run will append (kept in memory from the start, so a long
        paced run never stops to copy them)."""
        self.names = list(names)
        self.path = None if path is None else Path(path)
        self._data = np.zeros((max(int(rows), 1), len(self.names)))
        self._n = 0
        self._pending = 0
        self.flush_every = flush_every
        self._format = ",".join(["%.10g"] * len(self.names)) + "\n"
        self._fh = None
        if self.path is not None:
            with writing("file", self.path):
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._fh = open(self.path, "w")
                self._fh.write(",".join(self.names) + "\n")

    def append(self, row) -> None:
        if len(row) != len(self.names):
            raise ValueError(f"row has {len(row)} values, expected {len(self.names)}")
        if self._n == len(self._data):
            self._data = np.concatenate([self._data, np.zeros_like(self._data)])
        kept = self._data[self._n]
        kept[:] = row
        self._n += 1
        if self._fh is not None:
            self._write(self._format % tuple(kept.tolist()))
            self._pending += 1
            if self._pending >= self.flush_every:
                self.flush()

    def _write(self, text: str) -> None:
        try:
            self._fh.write(text)
        except OSError as exc:
            self._abandon()
            raise write_error("file", self.path, exc) from None

    def flush(self) -> None:
        self._pending = 0
        if self._fh is not None:
            try:
                with writing("file", self.path):
                    self._fh.flush()
            except OutputError:
                self._abandon()
                raise

    def _abandon(self) -> None:
        """Stop writing after a failed write (the file is incomplete; the caller says so)."""
        fh, self._fh = self._fh, None
        try:
            fh.close()
        except OSError:
            pass

    def close(self) -> None:
        self.flush()
        if self._fh is not None:
            fh, self._fh = self._fh, None
            with writing("file", self.path):
                fh.close()

    def columns(self) -> dict[str, np.ndarray]:
        data = self._data[:self._n].copy()
        return {name: data[:, i] for i, name in enumerate(self.names)}

    def __len__(self) -> int:
        return self._n
