"""random() and make_list(), the Script Directory's urmath functions that make a value: programs
call them (UR's examples seed lists with make_list), so a controller that lacks them refuses them."""

from __future__ import annotations

from .test_urscript_control import faults, run, said


def test_random_gives_floats_from_0_to_1_that_differ() -> None:
    _, events = run(
        "def prog():\n  i = 0\n  while i < 20:\n    textmsg(random())\n    i = i + 1\n  end\nend\n"
    )
    values = [float(text) for text in said(events)]
    assert len(values) == 20 and all(0 <= v <= 1 for v in values)
    assert len(set(values)) > 1


def test_random_with_an_argument_is_a_runtime_exception_at_its_line() -> None:
    _, events = run("def prog():\n  x = 1\n  y = random(3)\nend\n")
    assert faults(events) == [("random: takes no arguments, got 1", 3, 1)]


def test_make_list_gives_the_manuals_lists() -> None:
    _, events = run(
        "def prog():\n"
        '  textmsg(make_list(5, "a"))\n'
        "  textmsg(make_list(3, 0, 100))\n"
        "  textmsg(length(make_list(0, 0, 100)))\n"
        "  textmsg(make_list(2, p[0.1, 0, 0, 0, 0, 0]))\n"
        "end\n"
    )
    assert said(events) == [
        "[a, a, a, a, a]",
        "[0, 0, 0]",
        "0",
        "[p[0.1, 0, 0, 0, 0, 0], p[0.1, 0, 0, 0, 0, 0]]",
    ]


def test_make_list_of_structs_gives_each_element_its_own() -> None:
    _, events = run(
        "def prog():\n  l = make_list(2, struct(a=1))\n  l[0].a = 5\n  textmsg(l[0].a, l[1].a)\nend\n"
    )
    assert not faults(events)
    assert said(events) == ["51"]


def test_make_list_refuses_what_the_manual_rules_out() -> None:
    for call, message in (
        ("make_list(2, [1, 2])", "initial_value cannot be an array"),
        ("make_list(5, 0, 2)", "capacity 2 is less than length 5"),
        ("make_list(-1, 0)", "length must be an int"),
        ('make_list("3", 0)', "length must be an int"),
        ("make_list(3)", "missing argument initial_value"),
    ):
        _, events = run(f"def prog():\n  x = 1\n  l = {call}\nend\n")
        ((text, line, _),) = faults(events)
        assert text.startswith("make_list: ") and message in text and line == 3, (call, text)
