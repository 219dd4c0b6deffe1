"""construct building blocks that generated structs use beyond construct's own."""

from __future__ import annotations

from typing import Any

from construct import Adapter, Construct, GreedyString


class CsvAdapter(Adapter):  # type: ignore[misc]
    """A comma-separated ASCII string on the wire, a list of str in Python.

    Lossless: "a,b," (a trailing comma, as some clients send) is ["a", "b", ""].
    """

    def _decode(self, obj: str, context: Any, path: str) -> list[str]:
        return obj.split(",")

    def _encode(self, obj: list[str], context: Any, path: str) -> str:
        return ",".join(obj)


class LinesAdapter(Adapter):  # type: ignore[misc]
    """Newline-terminated names ("var_1\\nvar_2\\n") on the wire, a list of str in Python."""

    def _decode(self, obj: str, context: Any, path: str) -> list[str]:
        names = obj.split("\n")
        return names[:-1] if names and names[-1] == "" else names

    def _encode(self, obj: list[str], context: Any, path: str) -> str:
        return "".join(f"{name}\n" for name in obj)


def lines_string() -> Construct:
    """Newline-terminated names running to the end of the message."""
    return LinesAdapter(GreedyString("utf8"))


def csv_string() -> Construct:
    """A comma-separated list of names running to the end of the package."""
    return CsvAdapter(GreedyString("ascii"))


def package_struct(size_field: Construct, type_field: Construct, code: int, body: Construct) -> Construct:
    """A whole package: size (counting the header), a constant type, then the body.

    Building computes the size from the built body; parsing limits the body to it.
    """
    from construct import Const, FixedSized, Rebuild, Struct, this

    header_size = size_field.sizeof() + type_field.sizeof()
    return Struct(
        "size" / Rebuild(size_field, lambda ctx: header_size + len(body.build(ctx.body))),
        "type" / Const(code, type_field),
        "body" / FixedSized(this.size - header_size, body),
    )


def prefixed_or_rest(prefix: Construct) -> Construct:
    """A string with a length prefix that counts the rest exactly; otherwise the rest is the string.

    Some fields are sent both ways by real controllers and peers (spec key `fallback: rest`).
    Building writes the prefixed form.
    """
    from construct import FocusedSeq, PascalString, Select, Terminated

    exact = FocusedSeq("text", "text" / PascalString(prefix, "utf8"), Terminated)
    return Select(exact, GreedyString("utf8"))
