"""One error hierarchy, so callers catch `RtdeSpecError` and never a library's internals.

Every error carries where it happened (package, field, byte offset) and what was
expected versus found, so a message can say what, where and why.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

try:  # at import: out of descriptors, an import then would fail too
    import resource
except ImportError:  # not POSIX
    resource = None  # type: ignore[assignment]


MAX_SHOWN = 500
"""Characters of a value an error message shows (the whole value stays in `actual`)."""


class RtdeSpecError(Exception):
    """Root of every error this package raises on purpose."""

    def __init__(
        self,
        reason: str,
        *,
        package: str | None = None,
        field: str | None = None,
        offset: int | None = None,
        expected: Any = None,
        actual: Any = None,
        subject: str | None = None,
    ) -> None:
        self.reason = reason
        self.subject = subject  # what it is about when not a field: "file x.txt", "controller version"
        self.package = package
        self.field = field
        self.offset = offset
        self.expected = expected
        self.actual = actual
        super().__init__(self._render())

    def relocated(self, shift: int = 0, package: str | None = None) -> RtdeSpecError:
        """The same error seen from further out: offset moved by `shift`, package filled in."""
        return type(self)(
            self.reason,
            package=package or self.package,
            field=self.field,
            offset=None if self.offset is None else self.offset + shift,
            expected=self.expected,
            actual=self.actual,
            subject=self.subject,
        )

    def in_stream(self, offset: int, number: int) -> RtdeSpecError:
        """The error of one package of a stream: absolute offset, and which package it is."""
        moved = self.relocated(offset)
        moved.reason = f"{moved.reason} [package #{number}, starting at byte {offset}]"
        moved.args = (moved._render(),)
        return moved

    def extend(self, more: str) -> None:
        """Add what the fault meant further out (an output not written), after what it says."""
        self.args = (f"{self.args[0]}; {more}",)

    def _render(self) -> str:
        where = [] if self.subject is None else [self.subject]
        if self.package is not None:
            where.append(f"package {self.package}")
        if self.field is not None:
            where.append(f"field {self.field}")
        if self.offset is not None:
            where.append(f"byte offset {self.offset}")
        text = f"{', '.join(where)}: {self.reason}" if where else self.reason
        got = None if self.actual is None else str(self.actual)
        if got is not None and len(got) > MAX_SHOWN:  # a 70,000-character text was the message
            got = f"{got[: MAX_SHOWN - 40]}... ({len(got)} characters)"
        if self.expected is not None and got is not None:
            text += f" (expected {self.expected}, got {got})"
        elif self.expected is not None:  # nothing to show as got: "got None" would mislead
            text += f" (expected {self.expected})"
        elif got is not None:
            text += f" (got {got})"
        return text


class DecodeError(RtdeSpecError, ValueError):
    """Bytes that do not decode: truncated, corrupt, unknown or out of layout."""


class EncodeError(RtdeSpecError, ValueError):
    """A value that cannot be put on the wire: out of range, wrong type, not ASCII."""


class ProtocolError(RtdeSpecError):
    """A well-formed package that breaks the protocol's rules (sequence, ids, limits)."""


class RecipeError(RtdeSpecError, ValueError):
    """A recipe that cannot be used: unknown names, bad direction, bad file."""


class RtdeConnectionError(RtdeSpecError, ConnectionError):
    """Connecting to a controller failed, or it closed the connection; names host and port."""


class OutputError(RtdeSpecError, OSError):
    """An output that could not be written (a full disk): names the file, what was kept, errno kept."""

    def __init__(self, reason: str, *, errno: int | None = None, subject: str | None = None) -> None:
        super().__init__(reason, subject=subject)
        self.errno = errno


class UsageError(RtdeSpecError):
    """The command line or call asks for something unusable: a missing file, an unknown version."""


class VersionStringError(UsageError, ValueError):
    """A controller version that is no version ("bogus", "v5.4"): a ValueError, as int("x") is."""


class MissingDependencyError(UsageError, ImportError):
    """An optional dependency is not installed; the message names the extra that brings it."""


def install_hint(extra: str) -> str:
    """How to install an extra: from the checkout this package runs from (an editable
    install: `pip install -e ".[x]"` there), else the distribution from the index."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    if (root / "pyproject.toml").is_file() and (root / "spec").is_dir():
        where = "" if Path.cwd().resolve() == root else f" in {root}"
        return f'pip install -e ".[{extra}]"{where}'
    return f"pip install 'rtde_spec[{extra}]'"


def require(module: str, extra: str, what: str) -> Any:
    """Import an optional dependency, or raise MissingDependencyError naming the extra to install."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingDependencyError(
            f"{what} needs {module.split('.')[0]}, which is not installed: {install_hint(extra)}"
        ) from None


@dataclass(frozen=True)
class SpecIssue:
    """One problem found in a spec file: which file, where in it, and why."""

    file: str
    path: str
    reason: str
    line: int | None = None

    def __str__(self) -> str:
        at = f"{self.file}:{self.line}" if self.line else self.file
        return f"{at}: {self.path or '<root>'}: {self.reason}"


class SpecError(RtdeSpecError):
    """The YAML spec is invalid; holds every issue found, not just the first."""

    def __init__(self, issues: list[SpecIssue]) -> None:
        self.issues = list(issues)
        summary = "\n".join(f"  {issue}" for issue in self.issues)
        super().__init__(f"{len(self.issues)} spec problem(s):\n{summary}")

    def _render(self) -> str:  # the reason already holds the full list
        return self.reason

    def relocated(self, shift: int = 0, package: str | None = None) -> RtdeSpecError:
        return self  # spec problems are located by file and line, not byte offset


def out_of_descriptors() -> str:
    """What to say when the process is out of file descriptors (EMFILE): the limit and what to
    do (the bare OSError names whatever file the process happened to open: a module, a socket)."""
    try:
        limit = str(resource.getrlimit(resource.RLIMIT_NOFILE)[0]) if resource else "?"
    except (OSError, ValueError):
        limit = "?"
    return (
        f"out of file descriptors (ulimit -n {limit}): raise the limit (e.g. ulimit -n 1024) "
        "or run fewer --jobs"
    )
