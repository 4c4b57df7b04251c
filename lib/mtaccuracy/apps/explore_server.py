"""The explorer's server safety: a token (as Jupyter's), a cap on sessions, its own origins.

* **Token.** Every page and websocket needs the server's token: random
  (:func:`new_token`, 32 URL-safe characters) unless ``--token`` sets one, printed in the URL at
  start (``/?token=...``).  The first request carrying it gets a cookie (HttpOnly,
  SameSite=Strict, named for the port) that the later requests and the websocket carry; a request
  without either is sent to a page saying where the token is, and no app is built for it
  (:class:`TokenAuth`, Bokeh's own authentication hooks).
* **Sessions.** At most :data:`MAX_SESSIONS` live sessions: one more gets a one-line page
  instead of the app (:class:`SessionCap`), so that many open tabs or requests cannot stall it.
* **Origins.** The websocket accepts the explorer's own origins only: an environment's
  ``BOKEH_ALLOW_WS_ORIGIN``, which Bokeh lets replace them, is overridden
  (:func:`own_origins`).
"""

from __future__ import annotations

import hmac
import re
import secrets

import panel as pn
from bokeh.server.auth_provider import AuthProvider
from bokeh.settings import settings
from tornado.web import RequestHandler

#: The most sessions (browser tabs) served at once.
MAX_SESSIONS = 8
#: What ``--token`` takes: 16 to 128 letters, digits, ``-`` or ``_`` (a URL needs no escaping).
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9_-]{16,128}")
#: Where a request without the token is sent.
TOKEN_PAGE = "/token-required"


def new_token() -> str:
    """A random token: 24 bytes from :mod:`secrets`, 32 URL-safe characters."""
    return secrets.token_urlsafe(24)


def checked_token(token: str) -> str:
    """``token`` if it matches :data:`TOKEN_PATTERN`, else a ValueError saying what it takes."""
    if not isinstance(token, str) or not TOKEN_PATTERN.fullmatch(token):
        raise ValueError("a token is 16 to 128 letters, digits, '-' or '_' (omit --token for a "
                         "random one)")
    return token


class _TokenPage(RequestHandler):
    def get(self):
        self.set_status(403)
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.finish("The mtaccuracy explorer needs its token: open the URL it printed at start "
                    "(http://127.0.0.1:<port>/?token=...).\n")


class TokenAuth(AuthProvider):
    """Bokeh authentication: the user is known when the request carries the token.

    Parameters
    ----------
    token : str
        The server's token (:func:`checked_token`).
    port : int
        The server's port, in the cookie's name (browsers share cookies across ports).
    """

    def __init__(self, token: str, port: int):
        self.token, self.cookie = checked_token(token), f"mtaccuracy_explore_{int(port)}"
        super().__init__()

    def _user(self, handler):
        given = handler.get_argument("token", None)
        if given is not None and hmac.compare_digest(given.encode(), self.token.encode()):
            if handler.get_cookie(self.cookie) != self.token and \
                    hasattr(handler, "set_cookie") and not getattr(handler, "_headers_written",
                                                                   False):
                handler.set_cookie(self.cookie, self.token, httponly=True, samesite="Strict",
                                   path="/")
            return "reader"
        cookie = handler.get_cookie(self.cookie)
        if cookie is not None and hmac.compare_digest(cookie.encode(), self.token.encode()):
            return "reader"
        return None

    @property
    def get_user(self):
        """The user of a request: ``"reader"`` with the token, else None (sent to the page)."""
        return self._user

    @property
    def login_url(self):
        """Where a request without the token goes (a 403 page saying where the token is)."""
        return TOKEN_PAGE

    @property
    def login_handler(self):
        """The page at :data:`TOKEN_PAGE`."""
        return _TokenPage


class SessionCap:
    """At most ``limit`` live sessions; a session is freed when Bokeh destroys it.

    Parameters
    ----------
    limit : int
        The most sessions at once.
    """

    def __init__(self, limit: int = MAX_SESSIONS):
        self.limit, self.live = int(limit), set()

    def gate(self, factory, refused):
        """A factory building ``factory()`` while fewer than ``limit`` live, else ``refused()``."""
        def build():
            doc = pn.state.curdoc
            context = getattr(doc, "session_context", None)
            key = getattr(context, "id", None) or object()      # one per build
            if len(self.live) >= self.limit:
                return refused()
            self.live.add(key)
            if doc is not None:
                doc.on_session_destroyed(lambda _ctx: self.live.discard(key))
            return factory()
        return build


def own_origins() -> None:
    """Make Bokeh use each server's own websocket origins, whatever the environment says.

    Bokeh replaces a server's origin list by ``BOKEH_ALLOW_WS_ORIGIN`` when set; a value set
    in code comes before the environment, and an empty one makes Bokeh use the server's own.
    """
    settings.allowed_ws_origin.set_value([])
