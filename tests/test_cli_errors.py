"""Every error a user can cause in the CLI, with its exit code and what its message says (issue 21.9).

Each case: the command line (with the files and stdin it is given), the exit code, and parts
of the message that name what was wrong, where (file, line, offset, field, option) and what to
do. Exit codes as rtde_spec/cli/main.py documents them: 1 data or result, 2 usage, 3 capture
read everything but some input was damaged. Run in-process through main(), in a scratch folder,
against one emulator for the commands that connect.
"""

from __future__ import annotations

import io
import socket
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.cli.main import main

from .capture_files import Conversation, rtde_packages, write
from .helpers import DATA

TWO_OUTPUTS = (
    '<rtde_config><recipe key="fast"><field name="timestamp"/></recipe>'
    '<recipe key="slow"><field name="actual_q"/></recipe></rtde_config>'
)
FILES: dict[str, str | bytes] = {
    "text.pcap": "hello\n",
    "bad.xml": '<rtde_config><recipe key="a"><field name="timestamp"/>\n<oops</recipe></rtde_config>',
    "unknown.yaml": "recipes:\n  - fields: [timestamp, bogus_name]\n",
    "two.xml": TWO_OUTPUTS,
    "ur.xml": (DATA / "ur_client_config.xml").read_text(),
    "wrong.txt": "timestamp\nactual_q\n",
    "ok.csv": "timestamp,a\n0,1\n1,2\n",
    "extra.yaml": "outputs:\n  - name: x\n    type: NOPE\n",
    "extra_map.yaml": "my_field:\n  type: DOUBLE\n",  # fields as a mapping, not under outputs:
    "extra_list.yaml": "- my_field\n",
    "extra_bin.yaml": b"\xf6\x00\x01binary",
    "guide.txt": "just some text\n",
    "script.urs": "popup('hi')\n",
    "afile": "not a folder\n",
}


@dataclass
class Case:
    argv: list[str]
    code: int
    says: tuple[str, ...]
    stdin: bytes | None = None
    lines: int | None = None  # the message is this many lines (one per distinct problem)
    where: str = "err"  # err, or out for reports on stdout (validate)
    ids: list[str] = field(default_factory=list)


def c(code: int, *argv_and_says: str, stdin: bytes | None = None, lines: int | None = None) -> Case:
    """c(2, "decode", "zz", "--", "what it says", ...): argv before '--', message parts after."""
    cut = argv_and_says.index("--")
    return Case(list(argv_and_says[:cut]), code, argv_and_says[cut + 1 :], stdin=stdin, lines=lines)


REC = ("record", "--host", "127.0.0.1")
CASES: list[Case] = [
    # decode
    c(2, "decode", "zz", "--", "'zz' is neither a file nor hex", "give hex (e.g. 00045601), a file, or -"),
    c(2, "decode", "missing.bin", "--", "file missing.bin", "no such file", "check the path"),
    c(1, "decode", "0002", "--", "field size, byte offset 0", "smaller than the header", "expected >= 3"),
    c(1, "decode", "-", "--", "byte offset 0", "ends inside a package", "expected 4 bytes, got 3",
      stdin=b"000456"),
    c(1, "decode", "--protocol", "primary", "0000000a1000000003", "--", "truncated", "expected 10 bytes"),
    c(2, "decode", "00045601", "--format", "parquet", "--", "parquet output needs a file",
      "add -o FILE.parquet"),
    c(2, "decode", "text.pcap.hex", "--", "file text.pcap.hex", "no such file"),
    c(2, "decode", "00045601", "--recipe", "nothere.xml", "--", "--recipe nothere.xml", "no such recipe file",
      "comma list"),
    c(1, "decode", "00045601", "--recipe", "timestamp,actual_qq", "--", "field actual_qq",
      "unknown output field", "did you mean actual_q", "rtde-spec fields --direction output"),
    c(2, "decode", "00045601", "--from", "client", "--recipe", "ur.xml", "--", "file ur.xml",
      "3 recipes and 2 input recipes", "setp (input, 2 fields)", "pick one with --recipe-key KEY"),
    c(2, "decode", "00045601", "--recipe", "ur.xml", "--recipe-key", "out", "--", "no recipe keyed 'out'",
      "give one of those keys"),
    c(2, "decode", "late.pcap", "--", "pcap capture file", "rtde-spec capture late.pcap -o OUTDIR"),
    # capture
    c(2, "capture", "missing.pcap", "-o", "out", "--", "file missing.pcap", "no such file",
      "give pcap/pcapng files"),
    c(2, "capture", "text.pcap", "-o", "out", "--", "file text.pcap", "not a pcap or pcapng file"),
    c(2, "capture", "nowhere/*.pcap", "-o", "out", "--", "no capture files in nowhere/*.pcap",
      "a glob matched nothing"),
    c(1, "capture", "late.pcap", "-o", "out", "--", "data packages without a recipe (50 of 64 bytes)",
      "give the recipe with --recipe FILE", lines=2),
    c(3, "capture", "late.pcap", "-o", "out", "--recipe", "wrong.txt", "--",
      "not of the given recipe (64 bytes; the recipe's packages are 60): check --recipe (50 times, at ",
      lines=2),
    c(2, "capture", "late.pcap", "-o", "out", "--recipe", "nothere.txt", "--", "--recipe nothere.txt",
      "no such recipe file"),
    c(2, "capture", "late.pcap", "-o", "out", "--port-map", "30004=nope", "--",
      "unknown protocol 'nope' in --port-map", "expected rtde, primary"),
    # record, refused before connecting
    c(2, *REC, "--fields", "timestamp", "-o", "out.txt", "--", "-o out.txt", "use .csv, .parquet"),
    c(2, *REC, "--fields", "timestamp", "-o", "o.csv", "--frequency", "0", "--", "--frequency 0",
      "a rate in Hz above 0"),
    c(2, *REC, "--fields", "timestamp", "-o", "o.csv", "--duration", "-1", "--", "--duration -1",
      "give seconds above 0"),
    c(2, *REC, "--fields", "timestamp", "-o", "o.csv", "--samples", "0", "--", "--samples 0", "1 or more"),
    c(2, *REC, "--fields", "timestamp", "-o", "o.csv", "--split", "bogus", "--", "--split 'bogus'",
      "e.g. 60s, 10min"),
    c(2, *REC, "--fields", "timestamp", "-o", "o.csv", "--port", "70000", "--", "argument --port",
      "70000 is not a port number: give 0..65535"),
    c(2, *REC, "--recipe", "nothere.xml", "-o", "o.csv", "--", "--recipe nothere.xml", "no such recipe file",
      "--fields A,B"),
    c(2, *REC, "--recipe", "two.xml", "-o", "o.csv", "--", "file two.xml", "2 output recipes",
      "fast (output, 1 field), slow (output, 1 field)", "pick one with --recipe-key KEY"),
    # record, connecting
    c(1, *REC, "--port", "{primary}", "--fields", "timestamp", "-o", "o.csv", "--",
      "127.0.0.1:{primary} speaks the primary/secondary interface", "RTDE is on port 30004 (--port 30004)"),
    c(1, *REC, "--port", "{closed}", "--fields", "timestamp", "-o", "o.csv", "--",
      "127.0.0.1:{closed}: nothing accepts connections there", "check --host and --port"),
    c(1, *REC, "--port", "{rtde}", "--fields", "timestamp,bogus", "-o", "o.csv", "--",
      "bogus: unknown field"),
    # validate
    c(2, "validate", "missing.xml", "--", "recipe missing.xml", "no such recipe file", "comma list"),
    c(2, "validate", "bad.xml", "--", "file bad.xml", "not well-formed XML at line 2, column 5"),
    c(2, "validate", "timestamp", "--controller", "4.0.0", "--", "argument --controller",
      "4.0.0 belongs to no known product line", "known: cb3 (3.x)"),
    c(2, "validate", "timestamp", "--frequency", "fast", "--", "argument --frequency", "invalid float"),
    # fields
    c(2, "--extra-fields", "missing.yaml", "fields", "--", "--extra-fields missing.yaml", "no such file",
      "shaped like spec/rtde/fields.yaml"),
    c(1, "--extra-fields", "extra.yaml", "fields", "--", "extra.yaml:3", "unknown type 'NOPE'",
      "known: BOOL"),
    # a spec problem's list is printed as lines (it was one line, its newlines as \x0a)
    c(1, "--extra-fields", "extra_map.yaml", "fields", "--",
      "extra_map.yaml:", "my_field: unknown key 'my_field'", "holds `inputs:` and `outputs:`", lines=2),
    c(1, "--extra-fields", "extra_list.yaml", "fields", "--",
      "the file is a mapping (doc_ref, inputs, outputs), not a list", lines=2),
    c(1, "--extra-fields", "extra_bin.yaml", "fields", "--",
      "extra_bin.yaml: <root>: not UTF-8 text: byte 0xf6 at offset 0", lines=2),
    c(2, "fields", "--diff", "5.10", "4.0", "--", "argument --diff", "no known product line"),
    # serve
    c(2, "serve", "--rtde-port", "99999", "--", "argument --rtde-port", "give 0..65535"),
    c(2, "serve", "--rtde-port", "{rtde}", "--primary-port", "0", "--secondary-port", "0",
      "--dashboard-port", "-1", "--realtime-port", "-1", "--",
      "cannot listen on 127.0.0.1:{rtde}: address already in use", "0: any free port"),
    c(2, "serve", "--scenario", "missing.yaml", "--", "missing.yaml", "No such file"),
    c(2, "serve", "--model", "UR99", "--", "unknown arm model 'UR99'", "known: UR3"),
    # watch
    c(2, "watch", "--host", "127.0.0.1", "--script", "missing.urs", "--", "file missing.urs",
      "URScript file not found"),
    c(2, "watch", "--host", "127.0.0.1", "--port", "30011", "--script", "script.urs", "--", "read-only",
      "accepted on the primary and secondary ports (30001, 30002)"),
    c(1, "watch", "--host", "127.0.0.1", "--port", "{rtde}", "--timeout", "1", "--",
      "127.0.0.1:{rtde} speaks RTDE", "e.g. --port 30002"),
    c(1, "watch", "--host", "127.0.0.1", "--port", "{dashboard}", "--timeout", "2", "--",
      "speaks the dashboard server", "primary/secondary interface is on ports 30001"),
    c(1, "watch", "--host", "127.0.0.1", "--port", "{closed}", "--", "cannot connect",
      "check the address and that the port is one of the primary/secondary ports"),
    c(2, "watch", "--host", "127.0.0.1", "--port", "{closed}", "--foxglove", "70000", "--",
      "--foxglove 70000", "a port 0..65535"),
    # plot
    c(2, "plot", "missing.csv", "a", "-o", "x.png", "--", "file missing.csv", "no such file or folder",
      "the folder of `rtde-spec capture -o OUT`"),
    c(2, "plot", "ok.csv", "nope", "-o", "x.png", "--", "file ok.csv", "no column 'nope'",
      "the table has: timestamp, a"),
    c(2, "plot", "ok.csv", "a", "-o", "x.txt", "--", "-o x.txt", "end it in .png, .svg or .pdf"),
    # an output under a file: "the folder afile does not exist" (it does), or a listing "Not a directory"
    c(2, "plot", "ok.csv", "a", "-o", "afile/x.png", "--", "-o afile/x.png", "afile is a file, not a folder"),
    c(2, "capture", "late.pcap", "-o", "afile/out", "--", "afile/out: afile is a file, not a folder"),
    c(2, "demo", "-o", "afile/d", "--", "-o afile/d: afile is a file, not a folder"),
    c(2, "plot", "ok.csv", "a", "-o", "nowhere/x.png", "--", "the folder nowhere does not exist"),
    c(2, "plot", "ok.csv", "a", "--time", "zz", "-o", "x.png", "--", "no column 'zz'",
      "name the time column with --time COLUMN"),
    # spec import, wireshark
    c(2, "spec", "import", "missing.txt", "--", "file missing.txt", "no such file",
      "give the published document"),
    c(2, "spec", "import", "guide.txt", "--write", "--spec-dir", "nowhere", "--", "--spec-dir nowhere",
      "no spec here", "give --spec-dir path/to/spec"),
    c(2, "spec", "import", "guide.txt", "--", "cannot tell the document's form", "expected an RTDE guide"),
    c(2, "wireshark", "--install", "-o", "afile/plugins", "--", "-o afile/plugins",
      "cannot install the dissector there", "give -o a folder you can write to"),
]  # fmt: skip


@pytest.fixture(scope="module")
def ports() -> Iterator[dict[str, int]]:
    emu = EmulatorThread(
        EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, dashboard_port=0, realtime_port=None)
    ).start()
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        closed = s.getsockname()[1]  # nothing listens here once the socket is closed
    yield {**emu.ports, "closed": closed}
    emu.stop()


@pytest.fixture
def scratch(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    for name, content in FILES.items():
        path = tmp_path / name
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    for package in rtde_packages(50):  # a capture that starts after the setup exchange
        conv.send("server", package)
    write(tmp_path / "late.pcap", [conv])
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _id(case: Case) -> str:
    words = [a for a in case.argv if not a.startswith("{")][:5]
    return "-".join(words).replace("/", "_")[:60]


@pytest.mark.parametrize("case", CASES, ids=[_id(k) for k in CASES])
def test_error(
    case: Case,
    ports: dict[str, int],
    scratch: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    argv = [a.format(**ports) for a in case.argv]
    if case.stdin is not None:
        monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(case.stdin)))
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse refuses an option
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    text = out if case.where == "out" else err
    assert code == case.code, (argv, code, text)
    for part in case.says:
        assert part.format(**ports) in text, (argv, part, text)
    assert "Traceback" not in err
    problems = [line for line in err.splitlines() if line.strip().startswith(("problem:", "error:"))]
    if case.lines is not None:
        assert len([line for line in err.splitlines() if line.strip()]) == case.lines, err
    assert problems or "error" in err, err


def test_the_table_covers_every_subcommand_that_takes_input() -> None:
    covered = {case.argv[0] if not case.argv[0].startswith("--") else case.argv[2] for case in CASES}
    assert {"decode", "capture", "record", "validate", "fields", "serve", "watch", "plot", "spec",
            "wireshark"} <= covered  # fmt: skip
    assert len(CASES) >= 30


def test_validate_reports_an_unknown_name_on_stdout_with_exit_1(scratch: Path) -> None:
    code = main(["validate", "unknown.yaml", "--controller", "5.12.2"])
    assert code == 1


def test_exit_codes_are_documented_in_help(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    for part in ("0 success", "1 error in the data or result", "2 usage error", "3 capture read every input",
                 "--lenient gives 0", "130 interrupted"):  # fmt: skip
        assert part in text


def test_many_distinct_problems_are_cut_to_twenty_lines_and_counted() -> None:
    from rtde_spec.cli.capture_cmd import MAX_PROBLEMS, distinct

    same = [
        f"a:1-b:2: controller data package at 17000000{i:02d}.000000: not of the given recipe"
        for i in range(40)
    ]
    others = [f"a:1-b:2: message at 1700000000.{i:06d}: problem number {i}" for i in range(30)]
    lines = distinct(same + others)
    assert lines[0] == (
        "a:1-b:2: controller data package: not of the given recipe (40 times, at 1700000000.000000 .. "
        "1700000039.000000)"
    )
    assert len(lines) == MAX_PROBLEMS + 1 and lines[1] == others[0]
    assert lines[-1] == "... and 11 more distinct problems (11 in all)"
