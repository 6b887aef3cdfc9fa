"""Who may talk to the viewer: the address it binds and the token it demands.

Rules: the server binds 127.0.0.1 unless told otherwise; bound to any other address it demands
a token (a random one unless ``token`` is given), and ``token`` is demanded on any address. With
a token, every HTTP request (the page, its scripts and the websocket's upgrade) must carry it,
as ``?token=`` (the printed URL) or as the cookie the page sets on its first load; any other
request is answered 403, so a websocket without it never opens.
"""
import hmac
import ipaddress
import secrets

COOKIE = "vtksvdag_token"


def is_loopback(host):
    """True for 127.0.0.0/8, ::1 and ``localhost``."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def required_token(host, token=None):
    """The token the server demands: ``token`` if given (a non-empty string), a new random one
    when ``host`` is beyond loopback, else None (no token)."""
    if token is not None:
        if not isinstance(token, str) or not token or any(c.isspace() for c in token):
            raise ValueError(f"token must be a non-empty string without spaces, got {token!r}")
        return token
    return None if is_loopback(host) else secrets.token_urlsafe(24)


def token_middleware(token):
    """An aiohttp middleware answering 403 to every request without ``token`` (query or
    cookie); a request with it in the query gets the cookie, so the page's own requests (its
    scripts, the websocket) carry it."""
    from aiohttp import web

    expected = token.encode()

    def matches(value):
        return isinstance(value, str) and hmac.compare_digest(value.encode(), expected)

    @web.middleware
    async def check_token(request, handler):
        from_query = matches(request.query.get("token"))
        if not (from_query or matches(request.cookies.get(COOKIE))):
            return web.Response(status=403, text="403: this viewer needs its token (?token=...)\n")
        response = await handler(request)
        if from_query and isinstance(response, web.StreamResponse) and not response.prepared:
            response.set_cookie(COOKIE, token, httponly=True, samesite="Strict")
        return response

    return check_token
