"""The meta-model of spec/dashboard/commands.yaml: the dashboard server's commands and reply texts.

The emulator's dashboard server answers from it and a dissector can read it; codegen
writes the validated file to `_generated/dashboard.py`, so the installed package needs
no YAML. The file is read without YAML aliases; unknown keys, a command given twice,
a reply naming a value the file does not declare, or an unknown product line are
errors naming the file and the entry.
"""

from __future__ import annotations

import re
import string
from functools import cache
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from rtde_spec.metamodel.schema import Since, StrictModel

SPEC_FILE = "dashboard/commands.yaml"
Action = Literal[
    "query", "none", "log", "load", "loaded_program", "play", "stop", "pause", "quit", "shutdown",
    "power_on", "power_off", "brake_release", "unlock_protective_stop", "restart_safety",
    "load_installation", "set_user_role", "set_operational_mode", "clear_operational_mode",
]  # fmt: skip
Outcome = Literal["ok", "failed", "not_found"]


class ValueDoc(StrictModel):
    doc: str


class DashboardCommand(StrictModel):
    command: Annotated[str, Field(pattern=r"^[A-Za-z][A-Za-z ]*[A-Za-z]$")]
    argument: Annotated[str, Field(pattern=r"^[a-z_]+$")] | None = None
    quoted: bool = False  # the argument may come in double quotes, which are not part of it
    action: Action
    since: Since
    doc: str | None = None
    replies: dict[Outcome, str]

    @model_validator(mode="after")
    def _has_ok(self) -> DashboardCommand:
        if "ok" not in self.replies:
            raise ValueError(f"command {self.command!r} has no 'ok' reply")
        return self


class DashboardFile(StrictModel):
    doc_ref: str
    port: Annotated[int, Field(ge=1, le=65535)]
    product_lines: list[str]
    replaced_by: dict[str, str] = Field(default_factory=dict)  # product line -> what it has instead
    greeting: str
    unknown: str
    max_line_bytes: Annotated[int, Field(ge=64)]
    values: dict[str, ValueDoc]
    commands: list[DashboardCommand]

    @model_validator(mode="after")
    def _consistent(self) -> DashboardFile:
        seen: set[str] = set()
        for c in self.commands:
            if c.command in seen:
                raise ValueError(f"command {c.command!r} is given twice")
            seen.add(c.command)
            known = set(self.values) | ({c.argument} if c.argument else set())
            for outcome, text in c.replies.items():
                for name in _placeholders(text):
                    if name not in known:
                        raise ValueError(
                            f"{c.command!r} reply {outcome!r} names {{{name}}}, not a declared value"
                        )
        if _placeholders(self.unknown) - {"line"}:
            raise ValueError("the unknown reply may name only {line}")
        return self

    def outcome(self, command: DashboardCommand | None, reply: str) -> str | None:
        """Which of the command's replies `reply` is (ok, failed, not_found), "unknown" for the
        reply to a command the server does not know, None when no pattern matches."""
        if command is not None:
            for outcome, text in command.replies.items():
                if _pattern(text).fullmatch(reply):
                    return outcome
        return "unknown" if _pattern(self.unknown).fullmatch(reply) else None

    def find(self, line: str) -> tuple[DashboardCommand, str] | None:
        """The command a line is (longest command text first) and its argument."""
        for c in sorted(self.commands, key=lambda c: -len(c.command)):
            if line == c.command:
                return c, ""
            if c.argument and line.startswith(c.command + " "):
                return c, line[len(c.command) + 1 :].strip()
        return None


@cache
def _pattern(text: str) -> re.Pattern[str]:
    """A reply text as a regular expression: its {placeholders} match any text."""
    parts = [
        re.escape(lit) + ("(.*)" if name is not None else "")
        for lit, name, _, _ in string.Formatter().parse(text)
    ]
    return re.compile("".join(parts), re.S)


def _placeholders(text: str) -> set[str]:
    return {name for _, name, _, _ in string.Formatter().parse(text) if name}


def load_dashboard(root: Path | str) -> DashboardFile:
    """Load and validate dashboard/commands.yaml below spec root `root`; SpecError says what is wrong."""
    from rtde_spec.metamodel.loader import load_file

    return load_file(root, SPEC_FILE, DashboardFile)


@cache
def dashboard_spec() -> DashboardFile:
    """The built-in dashboard table, from the generated module."""
    from rtde_spec._generated.dashboard import DASHBOARD

    return DashboardFile.model_validate(DASHBOARD)
