"""The first numba compile of one of echocal's kernels is announced once on stderr."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

pytest.importorskip("numba")

from echocal._numba import _announcer


def _event(module: str) -> SimpleNamespace:
    dispatcher = SimpleNamespace(
        py_func=SimpleNamespace(__module__=module), _cache=SimpleNamespace(cache_path="/c")
    )
    return SimpleNamespace(data={"dispatcher": dispatcher})


def test_the_compile_notice_is_printed_once_and_only_for_echocal_kernels(capsys):
    listener = _announcer()
    listener.on_start(_event("someone.else"))  # another package's kernel: not ours to say
    assert capsys.readouterr().err == ""
    listener.on_start(_event("echocal.wave.sir"))
    listener.on_start(_event("echocal.echo"))  # a second kernel of the same process: silent
    err = capsys.readouterr().err
    assert err.count("echocal: compiling numba kernels") == 1 and "cached on disk in /c" in err
