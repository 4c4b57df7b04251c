"""``make lab``: JupyterLab on 127.0.0.1 with a token, as root too."""

import pytest

from mtaccuracy.compendium import lab


def test_root_gets_allow_root_and_the_lab_stays_local():
    cmd = lab.command("", uid=0)
    assert cmd[1] == "lab" and "--ip=127.0.0.1" in cmd and "--allow-root" in cmd
    assert "--allow-root" not in lab.command("", uid=1000)


def test_lab_args_are_split_not_evaluated():
    cmd = lab.command("--port 9999 --ServerApp.root_dir='a b'; touch x", uid=1000)
    assert cmd[-4:] == ["--port", "9999", "--ServerApp.root_dir=a b;", "touch", "x"][-4:]


@pytest.mark.parametrize("args, message", [
    ("--ip=0.0.0.0", "beyond this machine"), ("--ip 0.0.0.0", "beyond this machine"),
    ("--ServerApp.token=", "switch the token off"), ("--port 'open", "No closing quotation"),
])
def test_lab_args_that_would_expose_it_are_refused(args, message):
    with pytest.raises(lab.LabArgsError, match=message):
        lab.command(args, uid=0)


def test_make_lab_as_root_passes_allow_root(monkeypatch, capsys):
    calls = []
    monkeypatch.setattr(lab.os, "execv", lambda prog, argv: calls.append(argv))
    monkeypatch.setattr(lab.os, "getuid", lambda: 0)
    monkeypatch.setenv("LAB_ARGS", "--no-browser")
    assert lab.main() == 0
    assert calls and "--allow-root" in calls[0] and calls[0][-1] == "--no-browser"
    monkeypatch.setenv("LAB_ARGS", "--ip=0.0.0.0")
    assert lab.main() == 2 and "beyond this machine" in capsys.readouterr().err
