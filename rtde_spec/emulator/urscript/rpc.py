"""URScript's remote procedure calls: `proxy = rpc_factory("xmlrpc", url)`, then `proxy.name(args)`.

URCaps' preambles make these handles for their daemons (Robotiq's force/torque path server, UR
Connect, an RS-485 forwarder) and their program nodes call them. A call is real XML-RPC over HTTP,
made in a worker thread so the control loop never waits for a server: the calling thread waits,
step by step, as the controller's does, for at most CALL_TIMEOUT. A failed call (no server, no such
method, a fault) stops the program, as the Script Manual says; a handle no one calls costs nothing.

Values go as the manual's RPC section has them: numbers, bools, strings and lists as themselves, a
pose as a struct of x, y, z, rx, ry, rz (and such a struct comes back as a pose), a struct as a
struct. `closeXMLRPCClientConnection()` is the handle's own method: each call opens its connection,
so it has nothing to close.
"""

from __future__ import annotations

import http.client
import xmlrpc.client
from collections.abc import Callable, Generator
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any
from urllib.parse import urlsplit

from rtde_spec.emulator.urscript import eip
from rtde_spec.emulator.urscript.calls import Pose, arg, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import Expr, ScriptFault, Stmt

CALL_TIMEOUT = 30.0  # s of real time a call may take before it fails
MAX_PENDING = 16  # calls under way at once, all programs together; more are refused
POSE_KEYS = ("x", "y", "z", "rx", "ry", "rz")
MAX_DEPTH = 8  # lists and structs in one another, either way
_CALLS = ThreadPoolExecutor(max_workers=4, thread_name_prefix="urscript-rpc")
_pending: set[Future[Any]] = set()
Waiting = Generator[None, None, Any]


class RpcHandle:
    """The value rpc_factory gives: where the server is."""

    __slots__ = ("url",)

    def __init__(self, url: str) -> None:
        self.url = url

    def __repr__(self) -> str:
        return f"rpc_factory(xmlrpc, {self.url})"

    __str__ = __repr__


class _Transport(xmlrpc.client.Transport):
    """HTTP with a time-out (the standard transport has none)."""

    def make_connection(self, host: Any) -> http.client.HTTPConnection:
        connection = super().make_connection(host)
        connection.timeout = CALL_TIMEOUT
        return connection


def rpc_factory(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> RpcHandle:
    """A handle: nothing is connected until a call (URCaps make handles for daemons not running)."""
    kind, url = arg(stmt, args, kwargs, 0, "type"), arg(stmt, args, kwargs, 1, "url")
    if kind != "xmlrpc":
        raise ScriptFault(f'rpc_factory: type must be "xmlrpc", not {kind!r}', stmt.line, 1)
    if not isinstance(url, str) or not url:
        raise ScriptFault(f"rpc_factory: url must be a text, not {type_name(url)}", stmt.line, 1)
    return RpcHandle(url)


def call(expr: Expr, handle: Any, args: list[Any], kwargs: dict[str, Any]) -> Waiting:
    """`handle.name(args)`: the server's answer, once it comes (the thread waits meanwhile)."""
    name, line, column = str(expr.value), expr.line, expr.column
    if isinstance(handle, eip.EipHandle):  # an Ethernet/IP handle's method: answered at once
        return eip.call(handle, name, args, kwargs, line, column)
    if not isinstance(handle, RpcHandle):
        raise ScriptFault(f"Type error: {type_name(handle)} has no method {name}", line, column)
    if name == "closeXMLRPCClientConnection":
        return None  # each call had its own connection
    if kwargs:
        raise ScriptFault(f"{name}: a remote procedure takes its arguments in order", line, column)
    parts = urlsplit(handle.url)
    if parts.scheme != "http" or not parts.hostname:
        raise ScriptFault(
            f"{name}: the emulator calls http:// servers only, not {handle.url!r} (pstream is not modelled)",
            line,
            column,
        )
    if len(_pending) >= MAX_PENDING:
        raise ScriptFault(f"{name}: more than {MAX_PENDING} remote procedure calls at once", line, column)
    sent = [_to_wire(a, 0, line, column) for a in args]
    future = _CALLS.submit(_call, handle.url, name, sent)
    _pending.add(future)
    future.add_done_callback(_pending.discard)
    while not future.done():
        yield
    try:
        answer = future.result()
    except xmlrpc.client.Fault as fault:
        raise ScriptFault(f"XML-RPC {name}: {fault.faultString}"[:200], line, column) from None
    except (OSError, xmlrpc.client.Error, http.client.HTTPException, ValueError) as exc:
        raise ScriptFault(f"XML-RPC {name} to {handle.url}: {exc}"[:200], line, column) from None
    return _from_wire(answer, 0, name, line, column)


def _dump_i4(marshaller: xmlrpc.client.Marshaller, value: Any, write: Callable[[str], object]) -> None:
    if not xmlrpc.client.MININT <= value <= xmlrpc.client.MAXINT:
        raise OverflowError("int exceeds XML-RPC limits")
    write(f"<value><i4>{int(value)}</i4></value>\n")


class _Marshaller(xmlrpc.client.Marshaller):
    """Python's, but an int goes as <i4>, XML-RPC's original element, not <int>: what the
    xmlrpc-c library writes (the library UR's RPC manual page names), and the only one
    UnderAutomation's Universal Robots SDK 9.4 reads (it refuses <int> as unsupported)."""

    dispatch = dict(xmlrpc.client.Marshaller.dispatch)  # noqa: RUF012 - the base class has it so
    dispatch[int] = _dump_i4


def _call(url: str, name: str, args: list[Any]) -> Any:
    parts = urlsplit(url)
    handler = (parts.path + (f"?{parts.query}" if parts.query else "")) or "/RPC2"
    body = (
        "<?xml version='1.0'?>\n<methodCall>\n<methodName>"
        f"{xmlrpc.client.escape(name)}</methodName>\n{_Marshaller(None, False).dumps(tuple(args))}"
        "</methodCall>\n"
    )
    transport = _Transport()
    try:
        response = transport.request(parts.netloc, handler, body.encode("utf-8", "xmlcharrefreplace"))
    finally:
        transport.close()
    return response[0] if len(response) == 1 else response


def _to_wire(value: Any, depth: int, line: int, column: int) -> Any:
    if depth > MAX_DEPTH:
        raise ScriptFault(f"XML-RPC: values nest more than {MAX_DEPTH} deep", line, column)
    if isinstance(value, Pose):
        return dict(zip(POSE_KEYS, (float(v) for v in value), strict=True))
    if isinstance(value, list):
        return [_to_wire(v, depth + 1, line, column) for v in value]
    if isinstance(value, dict):
        return {str(k): _to_wire(v, depth + 1, line, column) for k, v in value.items()}
    if isinstance(value, bool | int | float | str):
        return value
    raise ScriptFault(f"XML-RPC: a {type_name(value)} cannot be sent", line, column)


def _from_wire(value: Any, depth: int, name: str, line: int, column: int) -> Any:
    if depth > MAX_DEPTH:
        raise ScriptFault(f"XML-RPC {name}: the answer nests more than {MAX_DEPTH} deep", line, column)
    if isinstance(value, dict):
        if sorted(value) == sorted(POSE_KEYS) and all(_number(v) for v in value.values()):
            return Pose(float(value[k]) for k in POSE_KEYS)
        return {str(k): _from_wire(v, depth + 1, name, line, column) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_from_wire(v, depth + 1, name, line, column) for v in value]
    if isinstance(value, bool | float | str):
        return value
    if isinstance(value, int):
        if not -(1 << 31) <= value < 1 << 31:
            raise ScriptFault(f"XML-RPC {name}: {value} is beyond URScript's 32-bit int", line, column)
        return value
    return str(value)  # a date or binary: as text


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)
