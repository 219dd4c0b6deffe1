"""The Flexible Ethernet/IP Adapter's handles (e-Series Script Directory chapter 20, from 5.16), as
UR's ethernet-ip/dmgmori example lays them out: labels defined on reader and writer handles, read
and written by name. No PLC is there: a reader reads zeros, a writer's values are checked and kept."""

from __future__ import annotations

import pytest

from .test_urscript_values import run_on

SETUP = (
    "def prog():\n"
    '  hwr = eip_writer_factory("111", 16)\n'
    '  hrd = eip_reader_factory("101", 16)\n'
    '  hwr.define_bit(0, 0, "RobotRequestComplete")\n'
    '  hwr.define_bit(0, 1, "AutoStart")\n'
    '  hwr.define_uint8(1, "code")\n'
    '  hwr.define_int16_array(2, 3, "axes")\n'
    '  hwr.define_string(8, 8, "name")\n'
    '  hrd.define_bit(0, 0, "comm_check")\n'
    '  hrd.define_bit(2, 9, "door_opened", 2)\n'
    '  hrd.define_uint16(2, "word")\n'
    '  hrd.define_float32_array(4, 2, "reals")\n'
)


def outcome(body: str, version: str = "5.16.0") -> tuple[list[str], list[tuple[str, int]]]:
    events = run_on(version, SETUP + body + "end\n")
    texts = [text for kind, text, _ in events if kind == "text"]
    return texts, [(text, line) for kind, text, line in events if kind == "runtime_exception"]


def test_labels_are_read_and_written_as_the_manual_shows() -> None:
    texts, faults = outcome(
        '  hwr.write(struct(AutoStart = True, code = 255, axes = [1, -2], name = "job 7"))\n'
        '  textmsg(hrd.read("comm_check"), hrd.read("reals"))\n'
        '  s = hrd.read(["door_opened", "word"])\n'
        "  textmsg(s.door_opened, s.word)\n"
        "  hrd.set_watchdog(2.5, 1)\n"
        "  hrd.stop_watchdog()\n"
        "  hrd.start_watchdog()\n"
        "  hwr.clear()\n"
        "  hwr.close()\n"
        '  textmsg("closed")\n'
        "  hwr.write(struct(code = 1))\n"
    )
    assert texts == ["False[0, 0]", "False0", "closed"]
    assert faults == [("write: the handle is closed (a new one has to be made)", 23)]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ('hwr.define_uint16(1, "over")', "'over' overlaps 'code'"),
        ('hrd.define_bit(3, 1, "again")', "'again' overlaps 'door_opened'"),  # bit 9 of the word at 2
        ('hwr.define_bit(9, 0, "in_text")', "'in_text' overlaps 'name'"),
        ('hwr.define_int32(14, "past")', "'past' does not fit in the instance's 16 bytes"),
        ('hwr.define_bit(0, 8, "b")', "bit_number must be 0 to 7 in a field of 1 bytes, not 8"),
        ('hwr.define_bit(0, 0, "b", 3)', "bitfield_width must be 1, 2 or 4, not 3"),
        ('x = hwr.read("code")', "a writer handle cannot be read"),
        ("hrd.write(struct(word = 1))", "a reader handle cannot be written"),
        ("hwr.write(struct(code = 256))", "256 is out of range for 'code' (uint8)"),
        ("hwr.write(struct(code = 1.5))", "1.5 is out of range for 'code' (uint8)"),
        ("hwr.write(struct(axes = [1, -40000]))", "-40000 is out of range for 'axes' (int16)"),
        ("hwr.write(struct(axes = [1, 2, 3, 4]))", "'axes' takes a list of 1 to 3 values"),
        ('hwr.write(struct(name = "eight ch"))', "'name' takes a text of at most 7 characters"),
        ("hwr.write(struct(AutoStart = 1))", "1 is out of range for 'AutoStart' (bit)"),
        ("hwr.write(struct(nope = 1))", "no label 'nope' defined on the handle"),
        ('x = hrd.read(["word", "nope"])', "no label 'nope' defined on the handle"),
        ("hrd.set_watchdog(11, 1)", "frequency must be over 0 and at most 10 Hz"),
        ("hrd.start_watchdog()", "no watchdog is registered"),
        ("hwr.set_watchdog(1, 1)", "only a reader handle has a watchdog"),
        ("hrd.clear()", "only a writer handle can be cleared"),
        ("hrd.resize(3)", "an Ethernet/IP handle has no method resize"),
        ("h = eip_reader_factory(101, 8)", "instance_name must be a text"),
        ('h = eip_writer_factory("111", 0)', "data_size must be an int of 1 to"),
    ],
)
def test_what_the_manual_rules_out_is_a_runtime_exception_at_its_line(line: str, problem: str) -> None:
    _, faults = outcome(f"  {line}\n")
    ((text, at),) = faults
    assert problem in text and at == 13, text


def test_the_factories_come_with_5_16() -> None:
    _, faults = outcome("", "5.15.0")
    assert faults == [("compile_error_name_not_found:eip_writer_factory:", 2)]
