"""The etorigami command."""

import subprocess
import sys

import pytest

from design.cli import main
from simulator import __version__


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert __version__ in capsys.readouterr().out


def test_help_lists_commands(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert "demo" in out and "usage" in out


def test_demo_runs_and_reports(capsys):
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "self_fold" in out and "gravity" in out and "converged" in out


def test_console_script_installed():
    out = subprocess.run([sys.executable, "-m", "design.cli", "--version"], capture_output=True,
                         text=True)
    assert out.returncode == 0 and __version__ in out.stdout


def test_bad_option_exits_nonzero():
    with pytest.raises(SystemExit) as info:
        main(["demo", "--residual-fold", "abc"])
    assert info.value.code == 2
