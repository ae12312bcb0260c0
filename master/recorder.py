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
from pantocosim.master.output_folder import writing


class Recorder:
    def __init__(self, path: Path | None, names: list[str], flush_every: int = 500):
        self.names = list(names)
        self.path = None if path is None else Path(path)
        self._rows: list[np.ndarray] = []
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
        row = np.asarray(row, dtype=float)
        if row.size != len(self.names):
            raise ValueError(f"row has {row.size} values, expected {len(self.names)}")
        self._rows.append(row)
        if self._fh is not None:
            self._write(self._format % tuple(row.tolist()))
            self._pending += 1
            if self._pending >= self.flush_every:
                self.flush()

    def _write(self, text: str) -> None:
        try:
            with writing("file", self.path):
                self._fh.write(text)
        except OutputError:
            self._abandon()
            raise

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
        data = np.vstack(self._rows) if self._rows else np.zeros((0, len(self.names)))
        return {name: data[:, i] for i, name in enumerate(self.names)}

    def __len__(self) -> int:
        return len(self._rows)
