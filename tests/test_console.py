"""The console script's start: ``import meshcorr`` is light, and Ctrl-C while the CLI loads is clean."""

import subprocess
import sys
import types

import pytest

import meshcorr
from meshcorr import _console


def test_importing_meshcorr_loads_no_numerical_library():
    code = "import sys, meshcorr; print('numpy' in sys.modules, 'scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_every_public_name_resolves():
    for name in meshcorr.__all__:
        assert getattr(meshcorr, name) is not None, name
    assert set(meshcorr.__all__) <= set(dir(meshcorr))
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        meshcorr.nothing  # noqa: B018


def test_ctrl_c_while_the_command_line_loads_exits_130_without_a_traceback(monkeypatch, capsys):
    # The interrupt arrives while `from .cli import main` runs (numpy and scipy loading).
    loading = types.ModuleType("meshcorr.cli")

    def interrupted(name):
        raise KeyboardInterrupt

    loading.__getattr__ = interrupted
    monkeypatch.setitem(sys.modules, "meshcorr.cli", loading)
    assert _console.main(["--version"]) == 130
    assert capsys.readouterr().err == "meshcorr: interrupted\n"


@pytest.mark.parametrize("interrupted", [True, False])
def test_an_import_error_is_an_interrupt_only_when_one_caused_it(monkeypatch, capsys, interrupted):
    # numpy re-raises whatever stops its own import (a Ctrl-C too) as an ImportError.
    loading = types.ModuleType("meshcorr.cli")

    def failing(name):
        try:
            raise KeyboardInterrupt if interrupted else OSError("libopenblas.so: cannot open shared object file")
        except BaseException as error:
            raise ImportError("Error importing numpy") from error

    loading.__getattr__ = failing
    monkeypatch.setitem(sys.modules, "meshcorr.cli", loading)
    if interrupted:
        assert _console.main(["--version"]) == 130
        assert capsys.readouterr().err == "meshcorr: interrupted\n"
    else:
        with pytest.raises(ImportError, match="Error importing numpy"):
            _console.main(["--version"])


def test_the_console_script_runs_the_command_line(capsys):
    with pytest.raises(SystemExit) as done:
        _console.main(["--version"])
    assert done.value.code == 0 and meshcorr.__version__ in capsys.readouterr().out
