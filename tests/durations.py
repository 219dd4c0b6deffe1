"""Longest test modules first, so the two pytest-xdist processes finish together.

`--dist loadfile` hands out whole modules as processes run dry. In collection order
(or xdist's own order, by number of tests) a module of a few long end-to-end tests
often comes last and one process runs it alone while the other idles: the plain run
took 3 min 48 s for 330 CPU-seconds on 2 cores. Sorting modules by their measured
seconds, longest first, is the classic longest-processing-time rule: the tail is
then short modules. `tests/durations.json` holds the seconds per module from a
quiet machine's run; modules missing from it (new ones) count as the median.

Refresh it after adding long tests (a wrong table only costs balance, never a test):

    python3 -m pytest -p no:cacheprovider --junitxml=/tmp/junit.xml
    python3 -m tests.durations /tmp/junit.xml
"""

from __future__ import annotations

import json
import statistics
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

TABLE = Path(__file__).with_name("durations.json")


def load() -> dict[str, float]:
    """Seconds per module path (tests/...py), or {} when there is no table."""
    try:
        table = json.loads(TABLE.read_text())
    except (OSError, ValueError):
        return {}
    return {str(k): float(v) for k, v in table.items()} if isinstance(table, dict) else {}


def module_of(nodeid: str) -> str:
    return nodeid.split("::", 1)[0]


def longest_first(nodeids: list[str], seconds: dict[str, float]) -> list[int]:
    """Indices of `nodeids` reordered: modules by seconds (descending), each module's tests
    kept together and in their own order; ties keep the collection order."""
    if not seconds:
        return list(range(len(nodeids)))
    default = statistics.median(seconds.values())
    first_seen: dict[str, int] = {}
    for i, nodeid in enumerate(nodeids):
        first_seen.setdefault(module_of(nodeid), i)

    def key(i: int) -> tuple[float, int, int]:
        module = module_of(nodeids[i])
        return (-seconds.get(module, default), first_seen[module], i)

    return sorted(range(len(nodeids)), key=key)


def from_junit(path: Path) -> dict[str, float]:
    """Seconds per module from a JUnit XML report (setup, call and teardown of every test)."""
    spent: dict[str, float] = {}
    for case in ET.parse(path).iter("testcase"):
        module = _module_path(case.get("classname") or "")
        spent[module] = spent.get(module, 0.0) + float(case.get("time") or 0.0)
    return {module: round(total, 1) for module, total in sorted(spent.items())}


def _module_path(classname: str) -> str:
    """tests.test_x or tests.test_x.TestClass -> tests/test_x.py (the longest part that is a file)."""
    parts = classname.split(".")
    for end in range(len(parts), 0, -1):
        path = "/".join(parts[:end]) + ".py"
        if (TABLE.parent.parent / path).is_file():
            return path
    return "/".join(parts) + ".py"


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python3 -m tests.durations JUNIT.xml", file=sys.stderr)
        return 2
    table = from_junit(Path(argv[0]))
    if not table:
        print(f"{argv[0]}: no test cases", file=sys.stderr)
        return 1
    TABLE.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    print(f"{TABLE}: {len(table)} modules, {sum(table.values()):.0f} s in all")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
