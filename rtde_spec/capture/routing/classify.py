"""Which protocol a captured TCP connection speaks: by port (defaults from the spec, or a
port map the user gives), else by its first bytes (an RTDE version request, a primary
version message, a real-time message of a known size), and the connection decoder for it.

Ports name the server's side: the controller's for RTDE, primary, real-time and the
dashboard; the driver PC's for URCL's external-control protocols (the robot connects
to it), so there the robot is the client.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache
from typing import Any

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec.capture.protocols.base import ConnectionDecoder
from rtde_spec.capture.tables.sink import TableSink
from rtde_spec.errors import UsageError

STREAM_KINDS = ("rtde", "primary", "realtime", "dashboard")  # the controller serves these
ROBOT_CLIENT_KINDS = ("reverse", "script_sender", "trajectory", "script_command")  # the driver serves these
KINDS = STREAM_KINDS + ROBOT_CLIENT_KINDS


@cache
def default_ports() -> dict[int, str]:
    """port -> protocol, every default the spec names.

    Read from the generated tables (validated at codegen time): a capture of RTDE alone
    builds no dashboard or external-control meta-model."""
    from rtde_spec._generated.dashboard import DASHBOARD
    from rtde_spec._generated.external_control import EXTERNAL_CONTROL
    from rtde_spec._generated.realtime import REALTIME_PORTS

    ports = {RTDE_PORT: "rtde", int(DASHBOARD["port"]): "dashboard"}
    ports.update({port: "primary" for port in PRIMARY_PORTS.values()})
    ports.update({port: "realtime" for port in REALTIME_PORTS.values()})
    ports.update({int(p["port"]): str(p["name"]) for p in EXTERNAL_CONTROL["protocols"]})
    return ports


def parse_port_map(items: Sequence[str]) -> dict[int, str]:
    """`50001=reverse,50003=trajectory` (items may repeat) -> {50001: "reverse", ...}."""
    out: dict[int, str] = {}
    for item in items:
        for pair in filter(None, (p.strip() for p in item.split(","))):
            port_text, sep, kind = pair.partition("=")
            if not sep or not port_text.strip().isdigit() or not 0 < int(port_text) < 65536:
                raise UsageError(f"bad --port-map entry {pair!r}: write PORT=PROTOCOL, e.g. 50001=reverse")
            if kind.strip() not in KINDS:
                raise UsageError(
                    f"unknown protocol {kind.strip()!r} in --port-map", expected=", ".join(KINDS)
                )
            out[int(port_text)] = kind.strip()
    return out


def port_kinds(
    rtde_ports: Sequence[int], primary_ports: Sequence[int], port_map: Mapping[int, str] | None
) -> dict[int, str]:
    """The ports of one run: the spec's defaults with the RTDE/primary lists and the map given."""
    ports = {p: k for p, k in default_ports().items() if k not in ("rtde", "primary")}
    ports.update({p: "rtde" for p in rtde_ports})
    ports.update({p: "primary" for p in primary_ports})
    ports.update(port_map or {})
    return ports


FIXED_RECORD_KINDS = ("reverse", "trajectory", "script_command", "realtime")  # records of one size


def fixed_record_ports(ports: Mapping[int, str]) -> frozenset[int]:
    """The ports whose connections carry records of one size (URCL's external control, the
    real-time interface): the reader finds runs of them in bulk (`bulk.runs`)."""
    return frozenset(port for port, kind in ports.items() if kind in FIXED_RECORD_KINDS)


def connection_for(
    kind: str, name: str, client: str, server: str, sink: TableSink, **kw: Any
) -> ConnectionDecoder:
    """The decoder of one connection of `kind`; the robot is the server but for external control."""
    if kind == "rtde":
        from rtde_spec.capture.protocols.rtde import RtdeConnection

        return RtdeConnection(name, server, sink, kw["recipe"], kw["catalogue"])
    if kind == "primary":
        from rtde_spec.capture.protocols.primary import PrimaryConnection

        return PrimaryConnection(name, server, sink, kw.get("session"))
    if kind == "realtime":
        from rtde_spec.capture.protocols.realtime import RealtimeConnection

        return RealtimeConnection(name, server, sink)
    if kind == "dashboard":
        from rtde_spec.capture.protocols.dashboard import DashboardConnection

        return DashboardConnection(name, server, sink)
    from rtde_spec.capture.protocols.external import ExternalConnection, ScriptSenderConnection
    from rtde_spec.metamodel.external import external_spec

    protocol = external_spec().protocol(kind)
    session = kw.get("session")  # shared by a capture file's connections: the programs sent to each robot
    if protocol.request is not None:
        return ScriptSenderConnection(name, client, sink, protocol, session)
    return ExternalConnection(name, client, sink, protocol, session)
