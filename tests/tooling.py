"""The one rule for a tool or library a test needs and this machine lacks: on CI (``CI`` set,
where .ci/run installs every system package the tests need) the test fails, elsewhere it is
skipped; either way the message names what is missing and how to install it."""

from __future__ import annotations

import os
import shutil
from typing import NoReturn

import pytest


def missing(what: str, install: str) -> NoReturn:
    """Fail on CI, skip elsewhere: ``what`` is missing (``install``: how to get it)."""
    if os.environ.get("CI"):
        pytest.fail(f"{what} is missing on CI ({install}; .ci/run installs it)")
    pytest.skip(f"{what} is missing ({install})")


def required(tool: str, package: str) -> str:
    """The path of the program ``tool`` (apt package ``package``)."""
    return shutil.which(tool) or missing(tool, f"apt-get install -y {package}")


def c_compiler() -> str:
    """The system's C compiler: ``$CC``, else ``cc``, else ``gcc``."""
    return (os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
            or missing("a C compiler", "apt-get install -y gcc"))
