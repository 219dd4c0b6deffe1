"""What a new user meets first: long arguments, comments, empty input, terminal safety,
exit codes, partial output, missing extras, capture files, peers' byte forms."""

from __future__ import annotations

import argparse
import json
import struct
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

from rtde_spec.cli.main import build_parser
from rtde_spec.primary.codec import PrimaryStreamDecoder, decode_message, encode_message
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.codec import build, decode

from .helpers import ROOT
from .test_cli import cli

OUTPUTS = RecipeCodec.for_names(["timestamp", "actual_q", "robot_mode"], "output")


def data_package(timestamp: float, recipe_id: int = 1) -> bytes:
    # hand-packed: header (size, 'U'), recipe id, DOUBLE, VECTOR6D, INT32
    payload = struct.pack(">d6di", timestamp, *([0.5] * 6), 7)
    return struct.pack(">HBB", 4 + len(payload), ord("U"), recipe_id) + payload


def ur5e_state_hex() -> str:
    import importlib.util

    spec = importlib.util.spec_from_file_location("ur5e", ROOT / "benchmarks/ur5e_robot_state.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return str(module.ur5e_robot_state_bytes().hex())


# 1. arguments of any length


def test_a_robot_state_of_1_4_kb_is_accepted_as_hex() -> None:
    text = ur5e_state_hex()
    assert len(text) > 2000
    result = cli("decode", "--protocol", "primary", text, "--json")
    assert result.returncode == 0, result.stderr
    (record,) = json.loads(result.stdout)
    assert record["package"] == "robot_state" and len(record["sub_packages"]) == 13


def test_a_2000_character_comma_list_validates_and_decodes() -> None:
    names = [f"output_double_register_{i}" for i in range(24, 48)]
    names += [f"output_int_register_{i}" for i in range(24, 48)]
    names += [f"output_bit_register_{i}" for i in range(64, 128)]
    text = ",".join(names)
    assert len(text) >= 2000
    result = cli("validate", text, "--controller", "5.12.2")
    assert "File name too long" not in result.stderr
    assert "setup limit" in result.stdout or "2048" in result.stdout or result.returncode == 0, result.stdout
    decoded = cli("decode", data_package(1.0).hex(), "--recipe", text)
    assert "File name too long" not in decoded.stderr
    assert "payload" in decoded.stderr  # the package is not of that recipe: a decode error, not a path error


# 2. recipe files with comments


def test_every_shipped_example_recipe_validates(tmp_path: Path) -> None:
    examples = resources.files("rtde_spec.examples")
    recipe = examples.joinpath("ur_rtde_default_outputs.txt")
    result = cli("validate", str(recipe), "--controller", "5.15.0")
    assert result.returncode == 0, result.stdout
    assert "unknown" not in result.stdout


def test_comments_in_line_and_comma_files(tmp_path: Path) -> None:
    lines = tmp_path / "lines.txt"
    lines.write_text("# recipe, for the arm\ntimestamp  # seconds\nactual_q\n\n# end\n")
    comma = tmp_path / "comma.txt"
    comma.write_text("# a comment, with a comma\ntimestamp,actual_q # trailing, too\n")
    for path in (lines, comma):
        result = cli("validate", str(path), "--controller", "5.12.2", "--json")
        assert result.returncode == 0, result.stdout
        report = json.loads(result.stdout)
        assert [f["name"] for f in report["recipes"][0]["fields"]] == ["timestamp", "actual_q"]
    package = RecipeCodec.for_names(["timestamp", "actual_q"], "output").encode_package(
        {"timestamp": 1.0, "actual_q": (0.0,) * 6}, 1
    )
    assert cli("decode", package.hex(), "--recipe", str(comma)).returncode == 0


# 3. empty input


@pytest.mark.parametrize("protocol", ["rtde", "primary"])
def test_empty_input_says_so(tmp_path: Path, protocol: str) -> None:
    empty = tmp_path / "empty.bin"
    empty.write_bytes(b"")
    for args, stdin in (([""], None), (["-"], b""), ([str(empty)], None)):
        result = cli("decode", *args, "--protocol", protocol, stdin=stdin)
        assert result.returncode == 1, (args, result.stdout)
        assert "no packages in the input" in result.stderr


# 4. nothing from the wire reaches the terminal raw


def test_control_characters_are_escaped_in_tables() -> None:
    package = build("text_message", message="\x1b[2J\x07bell\x00nul", source="a\x1bb", warning_level=1)
    result = cli("decode", package.hex())
    assert result.returncode == 0, result.stderr
    assert "\x1b" not in result.stdout and "\x07" not in result.stdout and "\x00" not in result.stdout
    assert "\\x1b[2J\\x07bell\\x00nul" in result.stdout


def test_control_characters_are_escaped_in_primary_trees() -> None:
    text = b"\x1b]0;owned\x07"
    body = struct.pack(">QbB", 1, -2, 0) + text
    message = struct.pack(">IB", 5 + len(body), 20) + body
    result = cli("decode", "--protocol", "primary", message.hex())
    assert result.returncode == 0, result.stderr
    assert "\x1b" not in result.stdout and "\\x1b]0;owned\\x07" in result.stdout


def _text_message(text: bytes) -> bytes:
    body = struct.pack(">QbB", 1, -2, 0) + text
    return struct.pack(">IB", 5 + len(body), 20) + body


@pytest.mark.parametrize("fmt", ["json", "jsonl", "csv", "mcap"])
def test_text_that_is_not_utf8_is_written_with_its_bytes_beside_it(fmt: str, tmp_path: Path) -> None:
    """A controller's text need not be UTF-8 (Latin-1 from a script): JSON and MCAP refused the
    decoder's surrogate escapes with a traceback, CSV with an error. Like capture tables, the
    text now has U+FFFD where the bytes are not UTF-8, and `<field>_raw` holds them in hex
    ('' for a good text, so the rows of one message keep one shape)."""
    stream = _text_message(b"ok") + _text_message(b"caf\xe9") + _text_message(b"done")
    out = tmp_path / f"texts.{fmt}"
    result = cli("decode", "--protocol", "primary", stream.hex(), "-o", str(out), "--format", fmt)
    assert result.returncode == 0, result.stderr
    if fmt == "mcap":
        from mcap.reader import make_reader

        with out.open("rb") as f:
            rows = [json.loads(m.data) for _, _, m in make_reader(f).iter_messages()]
    elif fmt == "csv":
        import csv

        rows = list(csv.DictReader(out.open(encoding="utf-8")))
    else:
        text = out.read_text(encoding="utf-8")
        rows = json.loads(text) if fmt == "json" else [json.loads(line) for line in text.splitlines()]
    assert [r["text_message"] for r in rows] == ["ok", "caf\ufffd", "done"]
    assert [r["text_message_raw"] for r in rows] == ["", b"caf\xe9".hex(), ""]


# 5. exit codes and help


def test_usage_errors_exit_2_everywhere(tmp_path: Path) -> None:
    assert cli("fields", "--controller", "banana").returncode == 2
    assert cli("validate", "timestamp", "--controller", "banana").returncode == 2
    assert cli("decode", "00045601", "--recipe", str(tmp_path)).returncode == 2
    result = cli("validate", str(tmp_path))
    assert result.returncode == 2 and "directory" in result.stderr and "Errno" not in result.stderr
    missing = cli("validate", str(tmp_path / "missing.xml"))
    assert missing.returncode == 2 and "no such recipe file" in missing.stderr
    assert "unknown output field" not in missing.stderr  # a path is not read as a field name
    assert cli("decode", str(tmp_path)).returncode == 2


def test_version_and_help_texts() -> None:
    from rtde_spec import __version__

    result = cli("--version")
    assert result.returncode == 0 and __version__ in result.stdout
    assert "0 valid" in cli("validate", "--help").stdout.replace("\n", " ")
    parser = build_parser()
    parsers = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            parsers += list(action.choices.values())
    for p in parsers:
        for action in p._actions:
            if (
                action.option_strings
                and action.help != argparse.SUPPRESS  # hidden: old spellings, global options repeated
                and not isinstance(action, (argparse._HelpAction, argparse._VersionAction))
            ):
                assert action.help and ("default" in action.help or "required" in action.help), (
                    p.prog,
                    action.option_strings,
                )


def test_controller_errors_say_controller_version() -> None:
    result = cli("fields", "--controller", "4.0.0")
    error = result.stderr.splitlines()[-1]
    assert "controller version 4.0.0" in error and "field " not in error.replace("rtde-spec fields", "")


# 6. partial results and absolute offsets


def test_packages_before_a_truncation_are_printed() -> None:
    stream = build("request_protocol_version", protocol_version=2) + build("start") + build("pause")[:-1]
    result = cli("decode", stream.hex(), "--from", "client", "--format", "jsonl")
    assert result.returncode == 1
    rows = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["package"] for r in rows] == ["request_protocol_version", "start"]
    assert "byte offset 8" in result.stderr and "truncated" in result.stderr


def test_recipe_errors_name_the_package_and_its_absolute_offset() -> None:
    good = data_package(1.0)
    short = data_package(2.0)[:-4]
    short = struct.pack(">H", len(short)) + short[2:]
    stream = good + good + short
    result = cli("decode", stream.hex(), "--recipe", "timestamp,actual_q,robot_mode", "--format", "jsonl")
    assert result.returncode == 1
    assert len(result.stdout.splitlines()) == 2  # the two good packages came out first
    start = 2 * len(good)
    assert f"package #3, starting at byte {start}" in result.stderr
    # the short payload ends inside robot_mode: 4 + 8 + 48 bytes into the package
    assert f"field robot_mode, byte offset {start + 4 + 56}" in result.stderr


# 7. missing optional dependencies


def test_decode_many_without_numpy_names_the_extra() -> None:
    code = (
        "import sys; sys.modules['numpy'] = None\n"
        "from rtde_spec.recipes.codec import RecipeCodec\n"
        "from rtde_spec.errors import MissingDependencyError\n"
        "codec = RecipeCodec.for_names(['timestamp'], 'output')\n"
        "try:\n    codec.decode_many(b'')\nexcept MissingDependencyError as exc:\n    print(exc)\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert '.[numpy]"' in result.stdout  # the extra, as a checkout (this one) installs it


# 8. capture files


@pytest.mark.parametrize(("magic", "kind"), [(b"\xd4\xc3\xb2\xa1", "pcap"), (b"\x0a\x0d\x0d\x0a", "pcapng")])
def test_a_capture_file_is_recognised(tmp_path: Path, magic: bytes, kind: str) -> None:
    path = tmp_path / f"capture.{kind}"
    path.write_bytes(magic + bytes(94))
    result = cli("decode", str(path))
    assert result.returncode == 2
    assert f"{kind} capture file" in result.stderr and "expected" not in result.stderr


# 9. agreement with real controllers' bytes


def version_message(major: int, minor: int) -> bytes:
    body = struct.pack(">QbB", 0, -2, 3) + struct.pack(">B", 9) + b"URControl"
    body += struct.pack(">BBii", major, minor, 0, 1) + b"date"
    return struct.pack(">IB", 5 + len(body), 20) + body


def test_a_cb2_era_controller_is_flagged_on_every_message() -> None:
    decoder = PrimaryStreamDecoder()
    messages = decoder.feed(version_message(1, 8) + bytes.fromhex(ur5e_state_hex()))
    assert str(decoder.version).startswith("1.8")
    for _, message in messages:
        warnings = decoder.warnings_for(message)
        assert "outside the spec's product lines" in warnings[0]
        assert "robot_mode_data" in warnings[0]  # decoded with the older layout python-urx documents
    modern = PrimaryStreamDecoder()
    for _, message in modern.feed(version_message(5, 15) + bytes.fromhex(ur5e_state_hex())):
        assert modern.warnings_for(message) == []


def test_layouts_that_disagree_are_flagged() -> None:
    state = bytes.fromhex(ur5e_state_hex())
    message = decode_message(state)
    subs = message.sub_packages
    shorter = subs[0].model_copy(update={"missing": ("x",)})
    longer = subs[1].model_copy(update={"extra": b"\x00"})
    mixed = message.model_copy(update={"sub_packages": [shorter, longer, *subs[2:]]})
    (warning,) = PrimaryStreamDecoder().warnings_for(mixed)
    assert "layouts disagree" in warning


def test_cli_shows_version_warnings() -> None:
    stream = version_message(1, 8) + bytes.fromhex(ur5e_state_hex())
    table = cli("decode", "--protocol", "primary", stream.hex())
    assert table.returncode == 0 and "warning: controller 1.8" in table.stdout
    rows = json.loads(cli("decode", "--protocol", "primary", stream.hex(), "--json").stdout)
    assert all("warnings" in r for r in rows)


def test_a_bool_byte_other_than_one_decodes_true_and_reencodes_as_one() -> None:
    # stated in docs/decisions.md: the guide's BOOL is 0 false, anything else true
    message = decode(bytes.fromhex("00045602"), sender="controller")
    assert message.accepted is True  # type: ignore[attr-defined]
    assert message.to_bytes() == bytes.fromhex("00045601")
    decisions = (ROOT / "docs" / "decisions.md").read_text()
    assert "re-encodes as 1" in decisions


def test_key_message_without_length_round_trips_in_the_documents_form() -> None:
    text = b"Protective stop: joint 3"
    body = struct.pack(">QbB", 0, -2, 7) + struct.pack(">II", 1, 2) + b"\x05Title" + text
    message = decode_message(struct.pack(">IB", 5 + len(body), 20) + body)
    assert message.key_text_message == text.decode()  # type: ignore[union-attr]
    again = decode_message(encode_message(message))
    assert again == message


def cb2_robot_state() -> bytes:
    """A CB2-era Robot State, packed with the struct formats python-urx reads software < 3.0 with."""
    mode = struct.pack(">Q7?Bd", 99, True, True, True, False, False, True, False, 7, 0.75)
    board = struct.pack(">hhbbddbbddffffB", 3, 5, 0, 1, 1.5, 2.5, 0, 1, 3.0, 4.0, 35.0, 48.0, 0.75, 0.0625, 1)
    board += b"\x01\x00"  # masterOnOffState, euromap67InterfaceInstalled: kept as extra bytes
    subs = b"".join(struct.pack(">IB", 5 + len(body), kind) + body for kind, body in ((0, mode), (3, board)))
    return struct.pack(">IB", 5 + len(subs), 16) + subs


def test_older_layouts_from_public_sources_decode_cb2_values() -> None:
    decoder = PrimaryStreamDecoder()
    ((_, _), (_, state)) = decoder.feed(version_message(1, 8) + cb2_robot_state())
    mode, board = state["robot_mode_data"], state["masterboard_data"]
    assert (mode.robot_mode, mode.target_speed_fraction, mode.timestamp) == (7, 0.75, 99)
    assert "control_mode" in mode.missing and mode.control_mode is None
    assert board.robot_voltage_48v == 48.0 and board.digital_output_bits == 5 and board.safety_mode == 1
    assert board.extra == b"\x01\x00"
    # without the version context the current layout would apply: the wrong values of the report
    wrong = decode_message(cb2_robot_state())["masterboard_data"]
    assert wrong.robot_voltage_48v != 48.0


def test_missing_fields_are_judged_by_their_since() -> None:
    # robot mode data as CB3 3.1 sends it (python-urx: !IBQ???????BBdd): no speed fraction limit
    body = struct.pack(">Q7?BBdd", 5, True, True, True, False, False, False, False, 7, 0, 1.0, 1.0)
    sub = struct.pack(">IB", 5 + len(body), 0) + body
    state = struct.pack(">IB", 5 + len(sub), 16) + sub
    old = PrimaryStreamDecoder()
    (_, (_, message)) = old.feed(version_message(3, 1) + state)
    assert set(message["robot_mode_data"].missing) == {"target_speed_fraction_limit", "reserved"}
    assert old.warnings_for(message) == []  # older than the fields' since on CB3: expected
    new = PrimaryStreamDecoder()
    (_, (_, message)) = new.feed(version_message(5, 15) + state)
    (warning,) = new.warnings_for(message)
    assert "robot_mode_data.target_speed_fraction_limit" in warning and "robot_mode_data.reserved" in warning


def test_a_stream_of_a_newer_controller_takes_the_straight_line_decoders() -> None:
    """After a Version message of 3.0 or newer, the sub-packages that have pre-3.0 layouts are
    still decoded by the generated decoders (the version picks their current layout); older
    versions take the general walk with the older layout."""
    import sys

    from rtde_spec.metamodel.versions import Version
    from rtde_spec.primary.codec import default_codec

    from .helpers import ROOT

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from ur5e_robot_state import ur5e_robot_state_bytes
    finally:
        sys.path.pop(0)
    codec = default_codec()
    state = ur5e_robot_state_bytes()
    reader = codec.robot_state
    assert reader.older_for(Version(5, 15, 0)) == frozenset() == reader.older_for(None)
    assert reader.older_for(Version(1, 8, 0)) == {0, 3}
    walked: list[str] = []
    general = reader.walk

    def counting(cls, *args):  # type: ignore[no-untyped-def]
        walked.append(cls.NAME)
        return general(cls, *args)

    reader.walk = counting
    try:
        decoder = PrimaryStreamDecoder(codec)
        ((_, _), (_, message)) = decoder.feed(version_message(5, 15) + state)
        old = PrimaryStreamDecoder(codec)
        old.feed(version_message(1, 8) + state)
    finally:
        reader.walk = general
    assert walked == ["robot_mode_data", "masterboard_data"]  # only for the 1.8 stream
    assert message == decode_message(state)


def closed(args: list[str], *redirect: str) -> subprocess.CompletedProcess[str]:
    """The command run with its standard streams as a shell's `>&-` (closed) or `2<FILE` leave them."""
    command = " ".join([sys.executable, "-m", "rtde_spec", *args, *redirect])
    return subprocess.run(["sh", "-c", command], capture_output=True, text=True, cwd=ROOT)


def test_a_command_started_with_stdout_or_stderr_closed_runs_and_refuses_only_data_it_would_lose(
    tmp_path: Path,
) -> None:
    """`>&-`: every print failed with a traceback (exit 1 after a capture had written its tables);
    a stderr descriptor a launcher had left on a read-only file (pyenv's shim) made every error
    message fail, a usage error exit 1. Now messages go nowhere and exit codes stand; data for
    standard output itself is refused, as it would be lost."""
    from tests.capture_files import Conversation, write

    capture = tmp_path / "one.pcap"
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    write(capture, [conv])
    assert closed(["fields"], ">&-").returncode == 0
    done = closed(["decode", "00045601", "--jsonl"], ">&-")
    assert done.returncode == 2 and "standard output is closed" in done.stderr, done.stderr
    for redirect in (">&-", "2>&-"):
        out = tmp_path / f"out{len(redirect)}"
        done = closed(["capture", str(capture), "-o", str(out), "--lenient"], redirect)
        assert done.returncode == 0, done.stderr
        assert (out / "rtde_setup").is_dir() and "Traceback" not in done.stderr
    assert closed(["decode", "nosuch.bin"], "2>&-").returncode == 2
    assert closed(["decode", "nosuch.bin"], f"2<{capture}").returncode == 2  # a read-only descriptor 2


def test_ctrl_c_while_the_command_starts_is_an_interrupt_not_a_traceback() -> None:
    """A KeyboardInterrupt while `python -m rtde_spec` imports the command line: exit 130."""
    code = (
        "import builtins, runpy\n"
        "real = builtins.__import__\n"
        "def importing(name, *args, **kwargs):\n"
        "    if name == 'rtde_spec.cli.main':\n"
        "        raise KeyboardInterrupt\n"
        "    return real(name, *args, **kwargs)\n"
        "builtins.__import__ = importing\n"
        "runpy.run_module('rtde_spec', run_name='__main__')\n"
    )
    done = subprocess.run([sys.executable, "-c", code, "fields"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 130 and done.stderr == "interrupted\n", done.stderr
