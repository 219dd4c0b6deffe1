"""rtde-spec examples: write the example files every command of the README names into a folder.

A newcomer has no capture, recipe or script yet; these ship in the package
(`rtde_spec/examples/files/`), so each README block runs as written from that folder.
Existing files are never overwritten unless --force says so.
"""

from __future__ import annotations

import argparse
from importlib import resources
from importlib.abc import Traversable
from pathlib import Path

from rtde_spec.cli.conventions import dangling_link, describe, place_copies
from rtde_spec.errors import UsageError

FILES = "files"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "examples",
        help="write the example files the README's commands use (captures, recipes, a script...)",
        **describe(
            "Writes the files every README command names into FOLDER: robot.pcapng (an RTDE and a "
            "primary connection), captures/ (two robots), late.pcap and its recipe outputs.txt, "
            "driver.pcap (a driver-like client's session with the emulator, captured on loopback: "
            "dashboard, primary, RTDE, 50001/50003/50004), rtde_config.xml, move.script, the "
            "scenario moving.yaml, byte files (session.bin, data.bin, capture_30001.bin) and an "
            "excerpt of a guide of our own (rtde-guide-5.30.txt). Run the README's commands from "
            "that folder. Existing files are left alone unless --force.",
            "rtde-spec examples rtde-examples/ && cd rtde-examples",
            "rtde-spec examples -o ~/rtde-try/ --force",
        ),
    )
    p.add_argument(
        "folder", nargs="?", metavar="FOLDER", help="where to write them (default: ./rtde-examples)"
    )
    p.add_argument("-o", "--output", metavar="FOLDER", help="the same as FOLDER (default: ./rtde-examples)")
    p.add_argument("--force", action="store_true", help="overwrite files of the same names (default: refuse)")
    p.set_defaults(run=run)


def shipped() -> list[tuple[str, Traversable]]:
    """(relative path, resource) of every shipped example file, sorted."""
    out: list[tuple[str, Traversable]] = []

    def walk(node: Traversable, prefix: str) -> None:
        for child in node.iterdir():
            name = f"{prefix}{child.name}"
            if child.is_dir():
                walk(child, f"{name}/")
            elif not child.name.startswith(("_", ".")):
                out.append((name, child))

    walk(resources.files("rtde_spec.examples").joinpath(FILES), "")
    return sorted(out, key=lambda item: item[0])


def run(args: argparse.Namespace) -> int:
    if args.folder and args.output and args.folder != args.output:
        raise UsageError(f"give the folder once: {args.folder!r} and -o {args.output!r} differ")
    given = args.output or args.folder or "rtde-examples"
    folder = Path(given)
    if folder.exists() and not folder.is_dir():
        raise UsageError("is a file, not a folder; give a folder to write the examples into", subject=given)
    broken = dangling_link(folder)
    if broken is not None:
        raise UsageError(broken, subject=given)
    files = shipped()
    clashes = [name for name, _ in files if (folder / name).exists()]
    if clashes and not args.force:
        raise UsageError(
            f"{len(clashes)} example file{'' if len(clashes) == 1 else 's'} already there "
            f"({', '.join(clashes[:4])}{', ...' if len(clashes) > 4 else ''}); "
            "give --force to overwrite them, or another folder",
            subject=given,
        )

    def refuse(why: str, target: Path) -> UsageError:  # the folder given is the problem
        return UsageError(
            f"cannot write the examples there ({target.relative_to(folder)}: {why}); "
            "give a folder you can write to",
            subject=given,
        )

    place_copies([(resource, folder / name) for name, resource in files], refuse)
    print(f"wrote {len(files)} example files to {folder}/: {', '.join(name for name, _ in files)}")
    print(f"run the README's commands from there: cd {folder}")
    return 0
