"""The test setup's own rule: a module the tests need is a skip on a
developer's machine but a failure under CI."""

import pytest

from conftest import need


def test_a_missing_module_fails_under_ci_and_skips_outside(monkeypatch):
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="missing under CI"):
        need("odocal_no_such_module")
    monkeypatch.delenv("CI")
    with pytest.raises(pytest.skip.Exception):
        need("odocal_no_such_module")
    assert need("json").dumps([1]) == "[1]"
