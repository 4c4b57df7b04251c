"""``make lab``: JupyterLab on 127.0.0.1 with a token, as root too.

The guard decides from the configuration jupyter_server would run with; every test runs with
its own, empty, Jupyter config folder (``JUPYTER_CONFIG_DIR``), data and runtime folders and
HOME, so that the developer's own ``~/.jupyter`` plays no part.
"""

import json
import os
import shlex
import time

import pytest

from mtaccuracy.compendium import lab

#: The option with which the lab's file browser starts in notebooks/.
START = "--FileContentsManager.preferred_dir=notebooks"


@pytest.fixture(autouse=True)
def own_jupyter(monkeypatch, tmp_path):
    """An empty Jupyter configuration, HOME and runtime for the test; returns its config dir."""
    home, config = tmp_path / "home", tmp_path / "jupyter-config"
    home.mkdir()
    config.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv("JUPYTER_CONFIG_DIR", str(config))
    monkeypatch.setenv("JUPYTER_DATA_DIR", str(tmp_path / "jupyter-data"))
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(tmp_path / "jupyter-runtime"))
    for name in ("JUPYTER_CONFIG_PATH", "JUPYTER_TOKEN", "JUPYTER_TOKEN_FILE", "IPYTHONDIR",
                 "LAB_UNSAFE", "LAB_ARGS"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.chdir(tmp_path)
    return config


def test_root_gets_allow_root_and_the_lab_stays_local():
    cmd = lab.command("", uid=0)
    assert cmd[1] == "lab" and "--ip=127.0.0.1" in cmd and "--allow-root" in cmd
    assert f"--notebook-dir={lab.paths.ROOT}" in cmd
    assert "--allow-root" not in lab.command("", uid=1000)


def test_the_lab_serves_the_repository_and_starts_in_notebooks():
    # the root is the repository, so that the files notebook 06 asks its reader to edit
    # (data/machines/*.csv) open in the lab; its file browser starts in notebooks/
    cmd = lab.command("", uid=1000)
    assert cmd[2:] == ["--ip=127.0.0.1", f"--notebook-dir={lab.paths.ROOT}", START]
    from jupyter_server.services.contents.filemanager import FileContentsManager
    manager = FileContentsManager(root_dir=str(lab.paths.ROOT),
                                  preferred_dir=START.split("=", 1)[1])
    assert lab.paths.ROOT / manager.preferred_dir == lab.paths.NOTEBOOKS
    assert manager.dir_exists("data/machines")


def test_lab_args_are_split_not_evaluated(tmp_path):
    url = "http://x/a b;$(touch pwned)`touch pwned`"
    cmd = lab.command(f"--port 9999 --ServerApp.custom_display_url='{url}'", uid=1000)
    assert cmd[-3:] == ["--port", "9999", f"--ServerApp.custom_display_url={url}"]
    assert not (tmp_path / "pwned").exists()


def test_a_quoting_error_is_refused():
    with pytest.raises(lab.LabArgsError, match="No closing quotation"):
        lab.command("--port 'open", uid=0)


# LAB_ARGS, the option the refusal must name, and the setting jupyter_server would end up with
EXPOSING = [
    ("--ip=0.0.0.0", "--ip=0.0.0.0", {"ip": "0.0.0.0"}),
    ("--ip 0.0.0.0", "--ip 0.0.0.0", {"ip": "0.0.0.0"}),
    ("--ServerApp.ip=*", "--ServerApp.ip=*", {"ip": ""}),
    ("--ip=''", "--ip=", {"ip": ""}),
    ("--ip=::", "--ip=::", {"ip": "::"}),
    ("--ip=lab.example.org", "--ip=lab.example.org", {"ip": "lab.example.org"}),
    ("--NotebookApp.ip=0.0.0.0", "--NotebookApp.ip=0.0.0.0", {"ip": "0.0.0.0"}),
    ("--LabApp.ip=0.0.0.0", "--LabApp.ip=0.0.0.0", {"ip": "0.0.0.0"}),
    ("--port 9999 --NotebookApp.ip 0.0.0.0", "--NotebookApp.ip 0.0.0.0", {"ip": "0.0.0.0"}),
    ("--ServerApp.allow_remote_access=True", "--ServerApp.allow_remote_access=True",
     {"allow_remote_access": True}),
    ("--IdentityProvider.token ''", "--IdentityProvider.token ''", {"auth_enabled": False}),
    ("--IdentityProvider.token=", "--IdentityProvider.token=", {"auth_enabled": False}),
    ("--ServerApp.token=", "--ServerApp.token=", {"auth_enabled": False}),
    ("--NotebookApp.token=", "--NotebookApp.token=", {"auth_enabled": False}),
    ("--ServerApp.password= --ServerApp.token=", "--ServerApp.token=",
     {"auth_enabled": False, "has_password": False}),
    ("--ServerApp.disable_check_xsrf=True", "--ServerApp.disable_check_xsrf=True",
     {"disable_check_xsrf": True}),
    ("--ServerApp.allow_origin=*", "--ServerApp.allow_origin=*", {"allow_origin": "*"}),
]


@pytest.mark.parametrize("args, culprit, effective", EXPOSING,
                         ids=[case[0] for case in EXPOSING])
def test_lab_args_that_would_expose_it_are_refused(args, culprit, effective):
    settings = lab.server_settings(shlex.split(args))
    assert {k: getattr(settings, k) for k in effective} == effective
    with pytest.raises(lab.LabArgsError) as refused:
        lab.command(args, uid=0)
    message = str(refused.value)
    assert message.startswith(f"LAB_ARGS option {shlex.join(shlex.split(culprit))} would ")
    assert "\n" not in message and f"{lab.UNSAFE_ENV}=yes" in message


@pytest.mark.parametrize("args", [
    "", "--port 9999 --no-browser", "--ServerApp.ip=localhost", "--ip=::1", "--ip=127.0.0.2",
    "--IdentityProvider.token=abc123", "--ServerApp.custom_display_url=http://example.org/lab",
    "--sock=lab.sock", "--ServerApp.foo=1",
    # a password protects the lab without a token
    "--ServerApp.password=sha1:0123:abcd --IdentityProvider.token=",
])
def test_harmless_lab_args_are_passed_on(args):
    cmd, extra = lab.command(args, uid=1000), shlex.split(args)
    assert cmd[1] == "lab" and cmd[len(cmd) - len(extra):] == extra
    settings = lab.server_settings(extra)
    assert lab.is_loopback(settings.ip) and settings.auth_enabled and settings.serves
    assert not settings.allow_remote_access


def test_the_defaults_give_way_to_the_same_option_in_lab_args(tmp_path):
    # jupyter refuses ServerApp.ip given twice, so --ip=::1 replaces --ip=127.0.0.1
    for args in ("--ip=::1", "--ServerApp.ip ::1"):
        cmd = lab.command(args, uid=1000)
        assert "--ip=127.0.0.1" not in cmd and f"--notebook-dir={lab.paths.ROOT}" in cmd
        assert START in cmd
        assert lab.server_settings(shlex.split(args)).ip == "::1"
    # another root: notebooks/ need not exist under it, so the starting folder gives way too
    for args in (f"--notebook-dir={tmp_path}", f"--ServerApp.root_dir={tmp_path}"):
        assert lab.command(args, uid=1000)[2:] == ["--ip=127.0.0.1", *shlex.split(args)]
    # a starting folder of the reader's own
    for args in (f"--preferred-dir={lab.paths.DATA}", "--FileContentsManager.preferred_dir=data",
                 "--ContentsManager.preferred_dir=data"):
        cmd = lab.command(args, uid=1000)
        assert cmd[2:] == ["--ip=127.0.0.1", f"--notebook-dir={lab.paths.ROOT}", args]


@pytest.mark.parametrize("args", [
    "--port=abc", "--bogus", "touch x", "--notebook-dir=no/such/folder",
    "--ip=::1 --ServerApp.ip=localhost",
])
def test_what_jupyter_itself_refuses_is_a_clear_error(args):
    with pytest.raises(lab.LabArgsError) as refused:
        lab.command(args, uid=1000)
    assert "\n" not in str(refused.value)


def test_options_with_which_jupyter_does_not_serve_pass(capsys):
    for args in ("--help", "--version"):
        assert not lab.server_settings([args]).serves
        assert lab.command(args, uid=1000)[-1] == args
    # with all the defaults given way, a first word such as `paths` is a JupyterLab subcommand
    args = ["paths", "--ip=::1", f"--notebook-dir={lab.paths.ROOT}"]
    assert lab.server_settings(args).argv[0] == "paths"
    assert not lab.server_settings(args).serves
    assert capsys.readouterr().out == ""   # the probe printed nothing


def test_a_legacy_login_handler_that_lets_everyone_in_is_refused(tmp_path, monkeypatch):
    # ServerApp.login_handler_class: jupyter_server falls back on LegacyIdentityProvider
    write(tmp_path / "mods" / "openlogin.py",
          "from jupyter_server.auth.login import LegacyLoginHandler\n\n\n"
          "class OpenLogin(LegacyLoginHandler):\n"
          "    @classmethod\n"
          "    def get_login_available(cls, settings):\n"
          "        return False\n")
    monkeypatch.syspath_prepend(str(tmp_path / "mods"))
    option = "--ServerApp.login_handler_class=openlogin.OpenLogin"
    assert not lab.server_settings([option]).auth_enabled
    with pytest.raises(lab.LabArgsError, match=f"^LAB_ARGS option {option} would "):
        lab.command(option, uid=1000)


def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("content, effective", [
    ('c.NotebookApp.ip = "0.0.0.0"\n', {"ip": "0.0.0.0"}),
    ('c.IdentityProvider.token = ""\n', {"auth_enabled": False}),
    ('c.ServerApp.token = ""\nc.ServerApp.password = ""\n', {"auth_enabled": False}),
    ('c.ServerApp.tornado_settings = {"xsrf_cookies": False}\n', {"disable_check_xsrf": True}),
])
def test_a_config_file_in_lab_args_is_read(tmp_path, content, effective):
    config = write(tmp_path / "cfg" / "risky.py", content)
    option = f"--config={config}"
    settings = lab.server_settings([option])
    assert {k: getattr(settings, k) for k in effective} == effective
    assert str(config) in settings.config_files
    with pytest.raises(lab.LabArgsError) as refused:
        lab.command(option, uid=1000)
    assert str(refused.value).startswith(f"LAB_ARGS option {option} would ")


def test_an_ip_the_command_line_overrides_is_let_through(tmp_path, own_jupyter):
    # jupyter reads the command line after the config files: --ip=127.0.0.1 wins over a
    # ServerApp.ip in any of them, and over LabApp.ip in JupyterLab's own config file
    config = write(tmp_path / "cfg" / "open.py", 'c.ServerApp.ip = "0.0.0.0"\n')
    write(own_jupyter / "jupyter_server_config.json", json.dumps({"ServerApp": {"ip": "::"}}))
    write(own_jupyter / "jupyter_lab_config.py", 'c.LabApp.ip = "0.0.0.0"\n')
    settings = lab.server_settings([f"--config={config}"])
    assert settings.ip == "127.0.0.1" and str(config) in settings.config_files
    assert str(own_jupyter / "jupyter_lab_config.py") in settings.config_files
    assert lab.command(f"--config={config}", uid=1000)[-1] == f"--config={config}"


@pytest.mark.parametrize("name, content", [
    ("jupyter_server_config.json", json.dumps({"NotebookApp": {"ip": "0.0.0.0"}})),
    ("jupyter_server_config.json", json.dumps({"IdentityProvider": {"token": ""}})),
    ("jupyter_server_config.py", 'c.ServerApp.token = ""\n'),
    ("jupyter_server_config.py", "c.ServerApp.allow_remote_access = True\n"),
    ("jupyter_server_config.py", 'c.LabApp.ip = "0.0.0.0"\n'),
    ("jupyter_lab_config.py", 'c.ServerApp.token = ""\n'),   # JupyterLab's own config file
    # the config file of another server extension, found through the environment's
    # etc/jupyter/jupyter_server_config.d: jupyter_server_terminals
    ("jupyter_jupyter_server_terminals_config.json", json.dumps({"ServerApp": {"token": ""}})),
])
def test_the_users_jupyter_config_is_read(own_jupyter, name, content):
    config = write(own_jupyter / name, content)
    with pytest.raises(lab.LabArgsError) as refused:
        lab.command("--port 9999", uid=1000)
    assert str(refused.value).startswith(f"Jupyter config file {config} would ")


def test_the_refusal_names_the_config_file_responsible(own_jupyter, tmp_path, monkeypatch):
    # loaded first (JUPYTER_CONFIG_DIR): a NotebookApp.ip; loaded last (JUPYTER_CONFIG_PATH,
    # the higher priority): a ServerApp.ip, which the command line's --ip overrides
    culprit = write(own_jupyter / "jupyter_server_config.py", 'c.NotebookApp.ip = "::"\n')
    other = write(tmp_path / "site" / "jupyter_server_config.json",
                  json.dumps({"ServerApp": {"ip": "0.0.0.0", "token": "abc"}}))
    monkeypatch.setenv("JUPYTER_CONFIG_PATH", str(other.parent))
    settings = lab.server_settings([])
    assert settings.ip == "::" and settings.config_files[-2:] == (str(culprit), str(other))
    with pytest.raises(lab.LabArgsError, match=f"^Jupyter config file {culprit} would "):
        lab.command("", uid=1000)


def test_lab_args_can_mend_the_users_jupyter_config(own_jupyter):
    write(own_jupyter / "jupyter_server_config.json", json.dumps({"ServerApp": {"token": ""}}))
    with pytest.raises(lab.LabArgsError):
        lab.command("", uid=1000)
    assert lab.command("--IdentityProvider.token=abc123", uid=1000)


def test_jupyter_config_path_and_token_file_are_read(tmp_path, monkeypatch):
    elsewhere = write(tmp_path / "elsewhere" / "jupyter_server_config.json",
                      json.dumps({"NotebookApp": {"ip": ""}}))
    monkeypatch.setenv("JUPYTER_CONFIG_PATH", str(elsewhere.parent))
    with pytest.raises(lab.LabArgsError, match=f"config file {elsewhere} would"):
        lab.command("", uid=1000)
    monkeypatch.delenv("JUPYTER_CONFIG_PATH")
    monkeypatch.setenv("JUPYTER_TOKEN_FILE", str(write(tmp_path / "token", "")))
    assert not lab.server_settings([]).auth_enabled
    with pytest.raises(lab.LabArgsError, match="^JUPYTER_TOKEN_FILE="):
        lab.command("", uid=1000)
    write(tmp_path / "token", "s3cret")
    assert lab.server_settings([]).has_token and lab.command("", uid=1000)


@pytest.mark.parametrize("value, passes", [
    ("yes", True), ("", False), ("no", False), ("YES", False), ("yes ", False), ("1", False),
    ("true", False),
])
def test_lab_unsafe_yes_is_the_one_way_past(monkeypatch, value, passes):
    monkeypatch.setenv("LAB_UNSAFE", value)
    if passes:
        cmd = lab.command("--ip=0.0.0.0", uid=1000)
        assert cmd[-1] == "--ip=0.0.0.0" and "--ip=127.0.0.1" not in cmd
    else:
        with pytest.raises(lab.LabArgsError):
            lab.command("--ip=0.0.0.0", uid=1000)


def test_make_lab_as_root_passes_allow_root(monkeypatch, capsys):
    calls = []
    monkeypatch.setattr(lab.os, "execv", lambda prog, argv: calls.append(argv))
    monkeypatch.setattr(lab.os, "getuid", lambda: 0)
    monkeypatch.setenv("LAB_ARGS", "--no-browser")
    assert lab.main() == 0
    assert calls and "--allow-root" in calls[0] and calls[0][-1] == "--no-browser"
    monkeypatch.setenv("LAB_ARGS", "--ip=0.0.0.0")
    assert lab.main() == 2 and "beyond this machine" in capsys.readouterr().err
    assert len(calls) == 1
    monkeypatch.setenv("LAB_UNSAFE", "yes")
    assert lab.main() == 0 and calls[-1][-1] == "--ip=0.0.0.0"
    assert "LAB_UNSAFE=yes" in capsys.readouterr().err


@pytest.mark.parametrize("setup", ["fresh", "used before", "logs to a file"])
def test_the_check_writes_nothing_and_leaves_no_trace(tmp_path, own_jupyter, setup):
    if setup == "used before":   # jupyter ran before: its runtime and data folders exist
        (tmp_path / "jupyter-runtime").mkdir()
        (tmp_path / "jupyter-data").mkdir()
    if setup == "logs to a file":   # jupyter would open the log file when it starts
        logging_config = {"handlers": {"file": {"class": "logging.FileHandler",
                                                "filename": str(tmp_path / "lab.log")}},
                          "loggers": {"ServerApp": {"handlers": ["file"]},
                                      "LabApp": {"handlers": ["file"]}}}
        write(own_jupyter / "jupyter_server_config.py",
              f"c.Application.logging_config = {logging_config!r}\n")
    before = sorted(p for p in tmp_path.rglob("*"))
    lab.command("--port 9999", uid=1000)
    with pytest.raises(lab.LabArgsError):
        lab.command("--NotebookApp.ip=0.0.0.0", uid=1000)
    # no runtime folder, cookie secret, ~/.ipython or data folder
    assert sorted(p for p in tmp_path.rglob("*")) == before
    assert "IPYTHONDIR" not in os.environ
    from jupyter_server.serverapp import ServerApp
    assert not ServerApp.initialized()


def test_the_check_is_quick():
    lab.server_settings([])   # the first call imports jupyter_server and JupyterLab
    start = time.perf_counter()
    lab.command("--port 9999 --no-browser", uid=1000)
    assert time.perf_counter() - start < 2


@pytest.mark.parametrize("host, local", [
    ("127.0.0.1", True), ("127.0.0.2", True), ("::1", True), ("localhost", True),
    ("LocalHost", True), ("0.0.0.0", False), ("", False), ("::", False), ("10.1.2.3", False),
    ("example.org", False),
])
def test_is_loopback(host, local):
    assert lab.is_loopback(host) is local
