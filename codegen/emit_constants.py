"""The spec's plain constants (ports, protocol versions, senders) as a module with no imports.

The command line reads them for its help text without loading pydantic or construct.
"""

from __future__ import annotations

from rtde_spec.spec.schema import Spec

from .render import PY_HEADER


def emit_constants(spec: Spec) -> str:
    pk = spec.packages
    protocols = tuple(sorted({p for m in pk.messages for p in m.protocols}))
    lines = [
        PY_HEADER,
        '"""Plain constants of the spec, importable without pydantic or construct."""\n\n',
        f"RTDE_PORT = {pk.port}\n",
        f"RTDE_PROTOCOLS: tuple[int, ...] = {protocols!r}\n",
        f"RTDE_SENDERS: tuple[str, ...] = {tuple(pk.senders)!r}\n",
        f"PRIMARY_PORTS: dict[str, int] = {dict(spec.primary.ports)!r}\n",
        "PRODUCT_LINES: dict[str, tuple[int, ...]] = {\n",
    ]
    for line in spec.product_lines.product_lines:
        lines.append(f"    {line.id!r}: {tuple(line.majors)!r},\n")
    lines.append("}\n")
    return "".join(lines)
