"""The text URScript makes of a value (`to_str`, `str_cat`, `textmsg`, `popup`,
`socket_send_string`): a pose shows as the manual writes one, `p[x, y, z, rx, ry, rz]`, and a
list of poses shows each as a pose; a joint list stays a plain `[...]`."""

from __future__ import annotations

import pytest

from .test_urscript_control import run


def said(script: str, steps: int = 50) -> list[str]:
    """What the program says (textmsg and popup), stepped as the server steps it."""
    _, events = run(script, steps)
    assert not [text for kind, text, _, _ in events if kind == "runtime_exception"]
    return [text for kind, text, _, _ in events if kind in ("text", "popup")]


def test_a_pose_shows_as_p_and_its_six_numbers() -> None:
    lines = said(
        "def prog():\n"
        "  x = p[0.1, -0.2, 0.3, 0, 3.14159, 0]\n"
        "  textmsg(to_str(x))\n"
        "  textmsg(x)\n"
        '  textmsg("at ", x)\n'
        '  textmsg(str_cat("tcp: ", x))\n'
        "  textmsg(to_str([x, x]))\n"
        "  textmsg(to_str([0.1, -0.2, 0.3, 0, 3.14159, 0]))\n"
        "end\n"
    )
    pose = "p[0.1, -0.2, 0.3, 0, 3.14159, 0]"
    assert lines == [
        pose,
        pose,
        f"at {pose}",
        f"tcp: {pose}",
        f"[{pose}, {pose}]",
        "[0.1, -0.2, 0.3, 0, 3.14159, 0]",  # six numbers without p: joints, a plain list
    ]


def test_poses_the_arm_gives_show_as_poses() -> None:
    (line,) = said("def prog():\n  textmsg(get_actual_tcp_pose())\nend\n")
    assert line.startswith("p[") and line.count(",") == 5


def test_a_float_shows_with_six_decimals_and_no_trailing_zeros() -> None:
    """The Script Directory's to_str and str_cat: "formatted with 6 decimals, and trailing zeros
    will be removed" (to_str(2.123456123456) is "2.123456"), not six significant digits: a client
    reading joints a program sends with socket_send_string gets them to the micro-radian."""
    lines = said(
        "def prog():\n"
        "  textmsg(to_str(2.123456123456))\n"
        "  textmsg(str_cat(-1.5707963, 123.4567891))\n"
        "  textmsg(p[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], [0.0000004, -0.0000004, 1234567.25])\n"
        "end\n"
    )
    assert lines == ["2.123456", "-1.570796123.456789", "p[1, 2, 3, 4, 5, 6][0, 0, 1234567.25]"]


def test_a_text_is_taken_apart_as_the_script_directory_s_examples_do() -> None:
    lines = said(
        "def prog():\n"
        '  textmsg(str_at("Hello", 1), str_empty(""))\n'
        '  textmsg(str_find("Hello World!", "o"), str_find("Hello World!", "o", 5))\n'
        '  textmsg(str_find("abc", "z"), str_empty("Hello"))\n'
        '  textmsg(str_sub("0123456789abcdefghij", 5, 3), str_sub("0123456789abcdefghij", 10))\n'
        '  textmsg(str_sub("abcde", 2, 50), str_sub("abcde", 5))\n'
        "end\n"
    )
    assert lines == ["eTrue", "47", "-1False", "567abcdefghij", "cde"]


@pytest.mark.parametrize(
    ("call", "problem"),
    [
        ('str_at("Hello", 10)', "index 10 is out of bounds (0 to 4)"),
        ('str_at("", 0)', "the source string is empty"),
        ('str_sub("abcde", -5, 50)', "index -5 is out of bounds"),
        ("str_find(1, 2)", "src must be a string, not int"),
    ],
)
def test_a_position_outside_the_text_is_a_runtime_exception(call: str, problem: str) -> None:
    _, events = run(f"def prog():\n  x = {call}\nend\n", 5)
    assert [(kind, line) for kind, _, line, _ in events if kind == "runtime_exception"] == [
        ("runtime_exception", 2)
    ]
    assert problem in next(text for kind, text, _, _ in events if kind == "runtime_exception")


def test_to_num_gives_an_int_without_a_decimal_point_hex_too() -> None:
    """The Script Directory's to_num: an int or a float by the presence of '.', an optional sign,
    "0x" hexadecimal; a number out of its type's range is a runtime exception."""
    lines = said(
        "def prog():\n"
        '  l = [10, 20, 30]\n  textmsg(l[to_num("+1")], to_num("0x3A"))\n'
        '  textmsg(to_num("3.14"), to_num(" -2"))\n'
        "end\n"
    )
    assert lines == ["2058", "3.14-2"]
    _, events = run('def prog():\n  x = to_num("99999999999")\nend\n', 5)
    assert [(kind, line) for kind, _, line, _ in events if kind == "runtime_exception"] == [
        ("runtime_exception", 2)
    ]


def test_a_struct_has_no_text_so_to_str_str_cat_and_textmsg_refuse_it() -> None:
    """The Script Directory's str_cat: operands "can be one of the following types: String, Boolean,
    Integer, Float, Pose, List of Boolean / Integer / Float / Pose. Any other type will raise an
    exception" (to_str lists the same); textmsg sends s1 and s2 "concatenated", as str_cat joins."""
    for call in ("to_str(s)", 'str_cat("s=", s)', 'textmsg("s=", s)', "textmsg(s)"):
        _, events = run(f"def prog():\n  s = struct(a=1)\n  x = 1\n  {call}\nend\n", 10)
        texts = [text for kind, text, _, _ in events if kind == "text"]
        (fault,) = [(text, line) for kind, text, line, _ in events if kind == "runtime_exception"]
        assert texts == [] and "a struct has no text" in fault[0] and fault[1] == 4, (call, fault)
    assert said('def prog():\n  textmsg(True, [False, 1, "a", 2.5])\nend\n') == ["True[False, 1, a, 2.5]"]
