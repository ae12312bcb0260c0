"""The rule for a missing tool (tests/tooling.py): fail on CI, skip elsewhere, name it."""

import pytest
from tooling import c_compiler, missing, required


@pytest.mark.parametrize("ci,outcome", [("", pytest.skip.Exception),
                                        ("true", pytest.fail.Exception)])
def test_a_missing_tool_skips_here_and_fails_on_ci(monkeypatch, ci, outcome):
    monkeypatch.setenv("CI", ci)
    with pytest.raises(outcome, match="no-such-tool-xyz is missing.*apt-get install -y pkg"):
        required("no-such-tool-xyz", "pkg")
    with pytest.raises(outcome, match="a C compiler is missing"):
        monkeypatch.setenv("CC", "")
        monkeypatch.setenv("PATH", "")
        c_compiler()
    with pytest.raises(outcome, match="thing is missing"):
        missing("thing", "how")


def test_a_present_tool_is_its_path():
    assert required("sh", "dash").endswith("/sh")
