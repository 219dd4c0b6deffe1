"""The plain run hands modules to its two processes longest first (tests/durations.py)."""

from __future__ import annotations

from pathlib import Path

from tests import durations

IDS = ["tests/a.py::x", "tests/a.py::y", "tests/b.py::x", "tests/c.py::x", "tests/c.py::y", "tests/d.py::x"]


def test_modules_go_longest_first_each_kept_whole_and_in_its_own_order() -> None:
    seconds = {"tests/a.py": 1.0, "tests/b.py": 9.0, "tests/c.py": 5.0}  # d.py unknown: the median, 5.0
    order = [IDS[i] for i in durations.longest_first(IDS, seconds)]
    assert order == ["tests/b.py::x", "tests/c.py::x", "tests/c.py::y", "tests/d.py::x",
                     "tests/a.py::x", "tests/a.py::y"]  # fmt: skip


def test_without_a_table_the_collection_order_stays() -> None:
    assert durations.longest_first(IDS, {}) == list(range(len(IDS)))


def test_the_table_is_read_from_a_junit_report(tmp_path: Path) -> None:
    report = tmp_path / "junit.xml"
    report.write_text(
        '<testsuites><testsuite><testcase classname="tests.test_cli" name="a" time="1.25"/>'
        '<testcase classname="tests.test_cli" name="b" time="0.5"/>'
        '<testcase classname="tests.faults.test_full_disk" name="c" time="2"/></testsuite></testsuites>'
    )
    assert durations.from_junit(report) == {"tests/faults/test_full_disk.py": 2.0, "tests/test_cli.py": 1.8}


def test_the_committed_table_names_only_modules_that_exist() -> None:
    table = durations.load()
    root = Path(durations.__file__).parent.parent
    assert table, "tests/durations.json is missing or empty"
    assert [m for m in table if not (root / m).is_file()] == []
