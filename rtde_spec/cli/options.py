"""Option groups several subcommands share, spelled once so they read the same in every `--help`."""

from __future__ import annotations

import argparse

from rtde_spec.cli.arguments import controller_version, port_number


def add_connection(p: argparse.ArgumentParser, port: int, port_help: str, timeout_help: str) -> None:
    """--host (required), --port and --timeout of a client of a controller (record, watch)."""
    p.add_argument("--host", required=True, metavar="ADDRESS", help="controller address (required)")
    p.add_argument(
        "--port", type=port_number, default=port, metavar="PORT", help=f"{port_help} (default: {port})"
    )
    p.add_argument(
        "--timeout", type=float, default=5.0, metavar="SECONDS", help=f"{timeout_help} (default: 5)"
    )


def add_controller(p: argparse.ArgumentParser, help_text: str) -> None:
    """--controller VERSION: MAJOR.MINOR.BUGFIX, an unknown release warned with the nearest known."""
    p.add_argument("--controller", metavar="VERSION", type=controller_version, help=help_text)


def add_lenient(p: argparse.ArgumentParser, help_text: str) -> None:
    """--lenient: keep going past damage (what was skipped is still reported)."""
    p.add_argument("--lenient", action="store_true", help=help_text)
