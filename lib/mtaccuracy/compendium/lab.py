"""``make lab``: JupyterLab on the repository, bound to 127.0.0.1 and protected by a token.

The command is ``jupyter lab --ip=127.0.0.1 --notebook-dir=<repository root>
--FileContentsManager.preferred_dir=notebooks``: the lab serves the whole repository, so that
the files a notebook asks its reader to edit (``data/machines/*.csv`` for notebook 06) open in
it too, and its file browser starts in ``notebooks/`` (JupyterLab's preferred folder, which
the folder button of the file browser's path bar returns to).  As root (containers, CI
machines) JupyterLab refuses to start without ``--allow-root``, which is added then.
``LAB_ARGS`` (from the environment, split like a shell would but never evaluated by one) is
appended, e.g. ``make lab LAB_ARGS="--port 9999 --no-browser"``.  Jupyter refuses an option
given twice, so ``--ip=127.0.0.1`` and ``--notebook-dir`` give way when ``LAB_ARGS`` sets the
same option itself (``--ip=::1``, ``--ServerApp.ip=localhost``), and the starting folder when
``LAB_ARGS`` sets a root or a preferred folder of its own (``notebooks`` need not exist under
another root); the checks below still apply.

Before JupyterLab starts, the configuration it would run with is worked out by jupyter_server's
and traitlets' own code (:func:`server_settings`): the same ``ServerApp``, with JupyterLab's
aliases and flags, parses the command line, loads the config files (``--config``,
``JUPYTER_CONFIG_DIR``, ``JUPYTER_CONFIG_PATH``, ``~/.jupyter``, the environment's
``etc/jupyter``) and links the server extensions, whose config is merged back into the server
(JupyterLab maps the old ``NotebookApp.*`` and ``LabApp.*`` names onto ``ServerApp``), and the
identity provider is built as the server builds it (``IdentityProvider.token``, the deprecated
``ServerApp.token``/``password``, ``PasswordIdentityProvider.hashed_password``,
``JUPYTER_TOKEN``/``JUPYTER_TOKEN_FILE``).  Nothing is started, bound, opened or written.
The lab is refused (:class:`LabArgsError`, ``make lab`` exits with status 2) when that
configuration would

* listen on anything but a loopback address (``ServerApp.ip`` empty or ``*``, ``0.0.0.0``,
  ``::``, a host name other than ``localhost``, ...);
* accept requests addressed to any host name (``ServerApp.allow_remote_access``);
* switch authentication off: no token and no password (``IdentityProvider.auth_enabled`` is
  false, the check behind jupyter_server's "All authentication is disabled" warning);
* switch the cross-site request forgery check off (``ServerApp.disable_check_xsrf``) or accept
  requests from any web site (``ServerApp.allow_origin='*'``): any page the browser opens could
  then drive the lab.

A UNIX socket (``--sock``) stays on this machine and keeps the token, so it is let through;
so is a ``c.ServerApp.ip`` in a config file, which the command line's ``--ip`` overrides.  Not
so ``NotebookApp.ip`` or ``LabApp.ip`` on the command line or in jupyter_server's config files:
JupyterLab hands those to the server after the command line has been read, and the server
listens there (in JupyterLab's own ``jupyter_lab_config`` the command line wins again; the
check follows jupyter's code, so it need not know such rules).  The message names the
``LAB_ARGS`` option or the config file responsible.  When JupyterLab itself would refuse the
arguments (an unknown option without a value, a value of the wrong type, an option given
twice, a file that does not exist), that refusal is reported the same way; an unknown
``--Class.trait=value`` only draws a warning from jupyter, and is passed on.  Config files
written in Python are run by the check as jupyter runs them.

The one way past the checks is the environment variable ``LAB_UNSAFE`` set to exactly ``yes``
(``make lab LAB_UNSAFE=yes LAB_ARGS="--ip=0.0.0.0"``): the notebooks run code, so only do this
on a network you trust.

Local imports: JupyterLab's server classes are imported when ``make lab`` starts it.
"""

from __future__ import annotations

import contextlib
import fnmatch
import io
import ipaddress
import logging
import os
import re
import shlex
import sys
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from . import paths

#: The environment variable that lets the lab start whatever it is configured to do.
UNSAFE_ENV = "LAB_UNSAFE"
#: The command's own options, each with the command-line settings (``Class.trait`` patterns)
#: it gives way to: the same trait, and for the starting folder any root or preferred folder.
_DEFAULTS = (
    ("--ip=127.0.0.1", {"ServerApp.ip"}),
    (f"--notebook-dir={paths.ROOT}", {"ServerApp.root_dir"}),
    (f"--FileContentsManager.preferred_dir={paths.NOTEBOOKS.relative_to(paths.ROOT).as_posix()}",
     {"*.root_dir", "*.notebook_dir", "*.preferred_dir"}),
)
#: Options with which ``jupyter lab`` prints something and stops (jupyter_server's
#: ``_preparse_for_stopping_flags``).
_STOPPING = ("-h", "--help", "--help-all", "--version", "-V", "--generate-config")
_ADVICE = (f"the lab stays on 127.0.0.1 behind its token (reach it from elsewhere through an "
           f"SSH tunnel), or set {UNSAFE_ENV}=yes to start it anyway")
#: For each refusal: the traits whose setting in a config file is to blame for it.
_TRAITS = {
    "ip": {"ip"},
    "remote": {"allow_remote_access", "tornado_settings"},
    "auth": {"token", "password", "hashed_password", "need_token", "identity_provider_class",
             "login_handler_class"},
    "xsrf": {"disable_check_xsrf", "tornado_settings"},
    "origin": {"allow_origin"},
}
_LOG = "mtaccuracy.compendium.lab.probe"


class LabArgsError(ValueError):
    """LAB_ARGS, or a Jupyter configuration, that the lab does not start with."""


@dataclass(frozen=True)
class ServerSettings:
    """What ``jupyter lab <argv>`` would do, as jupyter_server works it out.

    Attributes
    ----------
    argv : tuple of str
        The arguments after ``jupyter lab``.
    serves : bool
        False when jupyter would not start a server at all (``--help``, ``--version``,
        ``--generate-config``, a subcommand such as ``jupyter lab build``).
    ip : str
        ``ServerApp.ip``, the address the server listens on ('' is every interface).
    sock : str
        ``ServerApp.sock``, the UNIX socket it listens on instead, or ''.
    allow_remote_access : bool
        Whether requests addressed to any host name are accepted.
    auth_enabled : bool
        The identity provider's ``auth_enabled``: False means no token and no password.
    has_token, has_password : bool
        Whether a token, and a hashed password, are set.
    disable_check_xsrf : bool
        Whether the cross-site request forgery check is off.
    allow_origin : str
        ``ServerApp.allow_origin`` ('*' accepts requests from any web site).
    config_files : tuple of str
        The config files loaded, in loading order.
    """

    argv: tuple[str, ...]
    serves: bool = True
    ip: str = "127.0.0.1"
    sock: str = ""
    allow_remote_access: bool = False
    auth_enabled: bool = True
    has_token: bool = True
    has_password: bool = False
    disable_check_xsrf: bool = False
    allow_origin: str = ""
    config_files: tuple[str, ...] = ()
    _file_configs: tuple = field(default=(), repr=False, compare=False)


def is_loopback(host: str) -> bool:
    """Whether listening on ``host`` keeps the server on this machine.

    Parameters
    ----------
    host : str
        A ``ServerApp.ip`` value: an IPv4 or IPv6 address, a host name, or '' (every interface).

    Returns
    -------
    bool
        True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1); False for everything
        else, host names included (what they resolve to can change).

    Examples
    --------
    >>> is_loopback("::1"), is_loopback("127.0.0.2"), is_loopback("0.0.0.0"), is_loopback("")
    (True, True, False, False)
    """
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _jupyter() -> SimpleNamespace:
    """jupyter_server and JupyterLab, imported when needed (the import takes seconds)."""
    from jupyter_server.auth.identity import LegacyIdentityProvider, PasswordIdentityProvider
    from jupyter_server.auth.login import LoginHandler
    from jupyter_server.extension.manager import ExtensionManager
    from jupyter_server.serverapp import ServerApp
    from jupyterlab.labapp import LabApp
    from traitlets.config import Application, Config

    return SimpleNamespace(
        LegacyIdentityProvider=LegacyIdentityProvider,
        PasswordIdentityProvider=PasswordIdentityProvider, LoginHandler=LoginHandler,
        ExtensionManager=ExtensionManager, ServerApp=ServerApp, LabApp=LabApp,
        Application=Application, Config=Config)


def _probe_class(j: SimpleNamespace) -> type:
    """A ``ServerApp`` that only works out its configuration.

    It leaves out what the real one writes while it is configured: the IPython 3 config
    migration, the runtime and data folders (created when first named) and the cookie secret
    file.  A new class for every probe, since notebook_shim attaches attributes to the server's
    class.
    """
    from jupyter_core.paths import jupyter_data_dir, jupyter_runtime_dir
    from traitlets import default

    log = logging.getLogger(_LOG)

    class ServerApp(j.ServerApp):
        def migrate_config(self):
            pass

        def _runtime_dir_default(self):
            return jupyter_runtime_dir()

        def _data_dir_default(self):
            return jupyter_data_dir()

        @default("cookie_secret")
        def _probe_cookie_secret(self):
            return b""

        @default("log")
        def _probe_log(self):
            return log

    return ServerApp


@contextlib.contextmanager
def _quiet(j: SimpleNamespace, files: list):
    """Silence the probe and record each config file loaded as ``(name, config)`` in ``files``.

    While it runs, traitlets applications configure no logging handlers (which could open log
    files), IPython's folder is looked up without being created (notebook_shim asks for it),
    and notebook_shim's reordering of the extension manager is undone afterwards.
    """
    app_cls, manager = j.Application, j.ExtensionManager
    saved = {"_configure_logging": app_cls.__dict__["_configure_logging"],
             "_load_config_files": app_cls.__dict__["_load_config_files"]}
    sorted_extensions = manager.__dict__["sorted_extensions"]
    load = saved["_load_config_files"].__func__

    def recording(cls, *args, **kwargs):
        for config, name in load(cls, *args, **kwargs):
            files.append((name, config))
            yield config, name

    ipython = os.environ.get("IPYTHONDIR")
    log = logging.getLogger(_LOG)
    log.propagate = False
    log.setLevel(logging.WARNING)
    out = io.StringIO()
    errors: list[str] = []   # what the server logs at ERROR and above
    handler = logging.Handler(logging.ERROR)
    handler.emit = lambda record: errors.append(record.getMessage())
    log.addHandler(handler)
    try:
        app_cls._configure_logging = lambda self: None
        app_cls._load_config_files = classmethod(recording)
        if not (ipython and os.path.isdir(ipython)):
            os.environ["IPYTHONDIR"] = tempfile.gettempdir()
        with warnings.catch_warnings(), contextlib.redirect_stdout(out), \
                contextlib.redirect_stderr(out):
            warnings.simplefilter("ignore")
            yield SimpleNamespace(out=out, errors=errors)
    finally:
        for name, value in saved.items():
            setattr(app_cls, name, value)
        manager.sorted_extensions = sorted_extensions
        if ipython is None:
            os.environ.pop("IPYTHONDIR", None)
        else:
            os.environ["IPYTHONDIR"] = ipython
        log.removeHandler(handler)


def _defaults(app: Any, extra: list[str]) -> list[str]:
    """The command's own options that ``extra`` does not displace (jupyter_server refuses a
    trait given twice on the command line; :data:`_DEFAULTS`), found by the server's
    command-line parser."""
    try:
        flags, aliases = app.flatten_flags()
        loader = app._create_loader(extra, aliases, flags,
                                    classes=list(app._classes_with_config_traits()))
        config = loader.load_config()
    except (Exception, SystemExit):
        return []   # jupyter refuses ``extra`` whatever comes before it: let it say why alone
    given = [f"{cls}.{trait}" for cls, section in config.items() if isinstance(section, dict)
             for trait in section]
    return [option for option, displaced_by in _DEFAULTS
            if not any(fnmatch.fnmatchcase(g, p) for g in given for p in displaced_by)]


def _stops(argv: list[str], lab_app: type) -> bool:
    """Whether ``jupyter lab <argv>`` stops before it serves (help, version, a subcommand)."""
    head = argv[:argv.index("--")] if "--" in argv else argv
    return any(a in _STOPPING for a in head) or bool(
        argv and re.match(r"^\w(\-?\w)*$", argv[0]) and argv[0] in lab_app.subcommands)


def _identity_provider(app: Any, j: SimpleNamespace) -> Any:
    """The identity provider, built as ``ServerApp.init_configurables`` builds it."""
    cls, kwargs = app.identity_provider_class, {"parent": app, "log": app.log}
    if app.login_handler_class is not j.LoginHandler and cls is j.PasswordIdentityProvider:
        cls = j.LegacyIdentityProvider   # a custom LoginHandler: pre-2.0 authentication
        kwargs["login_handler_class"] = app.login_handler_class
        if app.logout_handler_class:
            kwargs["logout_handler_class"] = app.logout_handler_class
    return cls(**kwargs)


def _failure(said: SimpleNamespace) -> str:
    """The last error jupyter logged, else printed (argparse's, without the program name)."""
    logged = [m.strip().splitlines()[0] for m in said.errors if m.strip()]
    printed = [line.strip() for line in said.out.getvalue().splitlines() if line.strip()]
    argparse = [line for line in printed if re.match(r"^\S+: error: ", line)]
    last = (logged or argparse or printed or ["it stopped"])[-1]
    return re.sub(r"^\S+: error: ", "", last)


def server_settings(lab_args: list[str], *, allow_root: bool = False) -> ServerSettings:
    """The configuration ``jupyter lab`` would run with, worked out without starting it.

    The steps of ``LabApp.launch_instance`` up to the server's start, with jupyter_server's
    own code: ``ServerApp.instance`` with JupyterLab's aliases; ``JupyterApp.initialize``
    (parse the command line, load the config files, command line first);
    ``find_server_extensions`` and ``init_server_extensions`` (link the extensions:
    JupyterLab loads its config files and hands ``NotebookApp.*``, ``LabApp.*`` and its
    ``ServerApp.*`` settings back to the server); JupyterLab's extension-point config; the
    identity provider as ``init_configurables`` builds it.

    Parameters
    ----------
    lab_args : list of str
        The user's arguments, already split.
    allow_root : bool
        Whether ``--allow-root`` is added (before ``lab_args``).

    Returns
    -------
    ServerSettings
        The settings that decide who can reach the server.

    Raises
    ------
    LabArgsError
        When jupyter would stop with an error (an unknown option, a bad value, an option given
        twice, a missing file, a broken configuration).
    """
    j = _jupyter()
    files: list = []
    argv = list(lab_args)
    with _quiet(j, files) as said:
        probe = _probe_class(j)
        j.ServerApp.clear_instance()
        app = probe.instance(jpserver_extensions={j.LabApp.get_extension_package(): True})
        app.aliases.update(j.LabApp.aliases)
        try:
            argv = _defaults(app, lab_args) + ["--allow-root"] * allow_root + argv
            if _stops(argv, j.LabApp):
                return ServerSettings(tuple(argv), serves=False)
            keep = app.jpserver_extensions.copy()
            super(j.ServerApp, app).initialize(argv=argv)
            app.jpserver_extensions.update(keep)
            if app._dispatching:   # a jupyter-server-<name> subcommand
                return ServerSettings(tuple(argv), serves=False)
            if j.LabApp.load_other_extensions and "jpserver_extensions" not in \
                    j.LabApp.serverapp_config:
                app.find_server_extensions()
            app.init_server_extensions()
            app.update_config(j.Config(app.extension_manager.extension_points[j.LabApp.name]
                                       .config))
            provider = _identity_provider(app, j)
            tornado = app.tornado_settings
            ip = app.ip
            return ServerSettings(
                tuple(argv), ip=ip, sock=app.sock,
                # not looked up for other hosts (a name lookup can hang); they are refused
                allow_remote_access=bool(tornado.get("allow_remote_access",
                                                     app.allow_remote_access))
                if is_loopback(ip) else True,
                auth_enabled=bool(provider.auth_enabled), has_token=bool(provider.token),
                has_password=bool(getattr(provider, "hashed_password", "")),
                disable_check_xsrf=bool(tornado.get("disable_check_xsrf",
                                                    app.disable_check_xsrf))
                or not tornado.get("xsrf_cookies", True),
                allow_origin=app.allow_origin,
                config_files=tuple(name for name, _ in files),
                _file_configs=tuple(files))
        except SystemExit as stop:
            if not stop.code:
                return ServerSettings(tuple(argv), serves=False)
            message = _failure(said)
        except Exception as exc:   # what would be a traceback in jupyter lab
            message = f"{type(exc).__name__}: {exc}"
        finally:
            probe.clear_instance()
    given = f" with LAB_ARGS {shlex.join(lab_args)!r}" if lab_args else ""
    raise LabArgsError(f"jupyter lab would not start{given}: {message}")


def _problems(s: ServerSettings) -> list[tuple[str, str]]:
    """What ``s`` would expose, as ``(kind, what it would do)``."""
    if not s.serves:
        return []
    out = []
    if not is_loopback(s.ip):
        where = "every network interface" if s.ip == "" else s.ip
        out.append(("ip", f"would serve the notebooks on {where}, beyond this machine"))
    elif s.allow_remote_access:
        out.append(("remote", "would accept requests addressed to any host name "
                              "(allow_remote_access), letting pages from beyond this machine "
                              "reach the lab"))
    if not s.auth_enabled:
        out.append(("auth", "would switch the token off (no token and no password: anyone who "
                            "reaches the port can run code)"))
    if s.disable_check_xsrf:
        out.append(("xsrf", "would switch the cross-site request forgery check off, letting "
                            "any web page the browser opens drive the lab"))
    if s.allow_origin == "*":
        out.append(("origin", "would accept requests from any web site (allow_origin='*')"))
    return out


def _option(args: list[str], i: int) -> str:
    """``args[i]`` shown as the option it belongs to (with ``--name value``, both words)."""
    if i and not args[i].startswith("-") and args[i - 1].startswith("-") \
            and "=" not in args[i - 1]:
        return shlex.join(args[i - 1:i + 1])
    return shlex.join(args[i:i + 1])


def _from_files(kind: str, s: ServerSettings) -> str:
    """The config file (or environment variable) that a refusal found without LAB_ARGS comes
    from."""
    def culprit(trait: str, value: Any) -> bool:
        if kind == "ip":   # not a ServerApp.ip that the command line overrides
            return value in ({"", "*"} if s.ip == "" else {s.ip})
        if kind == "auth" and trait in ("token", "password", "hashed_password"):
            return value == ""
        return True

    for name, config in reversed(s._file_configs):
        if any(culprit(trait, value) for section in config.values()
               if isinstance(section, dict)
               for trait, value in section.items() if trait in _TRAITS[kind]):
            return f"Jupyter config file {name}"
    if kind == "auth" and os.environ.get("JUPYTER_TOKEN_FILE"):
        return f"JUPYTER_TOKEN_FILE={os.environ['JUPYTER_TOKEN_FILE']}"
    files = ", ".join(s.config_files)
    return f"the Jupyter configuration ({files})" if files else "the Jupyter configuration"


def _blame(kind: str, extra: list[str], settings: ServerSettings, allow_root: bool) -> str:
    """Who sets what ``kind`` refuses: the Jupyter configuration when it does so without
    LAB_ARGS, else the first LAB_ARGS option from which on it appears."""
    try:
        base = server_settings([], allow_root=allow_root) if extra else settings
    except LabArgsError:
        base = ServerSettings(())
    if any(k == kind for k, _ in _problems(base)):
        return _from_files(kind, base)
    for i in range(len(extra)):
        try:
            upto = server_settings(extra[:i + 1], allow_root=allow_root)
        except LabArgsError:
            continue   # an option waiting for its value
        if any(k == kind for k, _ in _problems(upto)):
            return f"LAB_ARGS option {_option(extra, i)}"
    return f"LAB_ARGS {shlex.join(extra)}"


def _split(lab_args: str) -> list[str]:
    try:
        return shlex.split(lab_args)
    except ValueError as exc:
        raise LabArgsError(f"LAB_ARGS={lab_args!r}: {exc}") from None


def command(lab_args: str = "", *, uid: int | None = None,
            unsafe: bool | None = None) -> list[str]:
    """The JupyterLab command line for ``lab_args``, checked as the module docstring says.

    Parameters
    ----------
    lab_args : str
        The user's options (``LAB_ARGS``), split with :func:`shlex.split`.
    uid : int, optional
        The user the lab runs as (default: ours); 0 adds ``--allow-root``.
    unsafe : bool, optional
        Skip the checks (default: whether ``LAB_UNSAFE`` is exactly ``yes``).

    Returns
    -------
    list of str
        ``[.../jupyter, "lab", ...]``, ready for :func:`os.execv`.

    Raises
    ------
    LabArgsError
        When ``lab_args`` cannot be split, jupyter would refuse them, or the configuration would
        expose the lab (the message names the option or config file and what it would do).
    """
    uid = os.getuid() if uid is None else uid
    unsafe = os.environ.get(UNSAFE_ENV) == "yes" if unsafe is None else unsafe
    extra = _split(lab_args)
    jupyter = Path(sys.executable).with_name("jupyter")
    if unsafe:
        j = _jupyter()
        with _quiet(j, []):
            app = _probe_class(j)()
            app.aliases.update(j.LabApp.aliases)
            args = _defaults(app, extra) + ["--allow-root"] * (uid == 0) + extra
        return [str(jupyter), "lab", *args]
    settings = server_settings(extra, allow_root=uid == 0)
    found = _problems(settings)
    if found:
        kind, what = found[0]
        raise LabArgsError(f"{_blame(kind, extra, settings, uid == 0)} {what}; {_ADVICE}")
    return [str(jupyter), "lab", *settings.argv]


def main() -> int:
    """Start JupyterLab as ``make lab`` does (replaces this process).

    Returns
    -------
    int
        2 when the lab is refused (the reason is printed on stderr); otherwise the process
        becomes JupyterLab and does not return.
    """
    try:
        cmd = command(os.environ.get("LAB_ARGS", ""))
    except LabArgsError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if os.environ.get(UNSAFE_ENV) == "yes":
        print(f"warning: {UNSAFE_ENV}=yes: LAB_ARGS and the Jupyter configuration are not "
              f"checked; the lab may be reachable beyond this machine", file=sys.stderr)
    print("==> " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    os.execv(cmd[0], cmd)
    return 0  # pragma: no cover - execv does not return


if __name__ == "__main__":
    raise SystemExit(main())
