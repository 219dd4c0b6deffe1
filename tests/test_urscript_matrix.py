"""URScript's matrices, as the Script Manual's "Matrix and Array Expressions" has them (3.14 / 5.9
on): a matrix is written as its rows, `[[1, 2], [3, 4], [5, 6]]`; `m[i, j]` reads and writes one
entry (0-indexed, row then column); a matrix times a matrix or an array is the matrix product; a
number applies to every entry. ur_rtde's control script for 5.23 and later reads the arm's model
this way (`write_output_float_reg(0, mass_matrix[0, 0])`)."""

from __future__ import annotations

import pytest

from rtde_spec.emulator.urscript import parse
from rtde_spec.emulator.urscript.nodes import ScriptFault
from tests.test_urscript_control import faults, said
from tests.test_urscript_control import run as run_script

ROWS = "m = [[1, 2], [3, 4], [5, 6]]\n"


def test_an_entry_is_read_by_row_and_column() -> None:
    _, events = run_script(ROWS + "textmsg(m[0, 0])\ntextmsg(m[2, 1])\ntextmsg(m[1, 0] + m[0, 1])\n")
    assert said(events) == ["1", "6", "5"] and not faults(events)


def test_an_entry_is_written_by_row_and_column_and_the_matrix_is_a_value() -> None:
    _, events = run_script(ROWS + "kept = m\nm[2, 1] = 20\ntextmsg(m)\ntextmsg(kept[2, 1])\n")
    assert said(events) == ["[[1, 2], [3, 4], [5, 20]]", "6"] and not faults(events)


@pytest.mark.parametrize(
    ("expression", "line_text"),
    [("m[3, 0]", "[3, 0]"), ("m[0, 2]", "[0, 2]"), ("m[-1, 0]", "[-1, 0]")],
)
def test_an_index_outside_the_matrix_is_the_runtime_error_at_its_line(
    expression: str, line_text: str
) -> None:
    model, events = run_script(ROWS + "textmsg(1)\nx = " + expression + "\ntextmsg(2)\n")
    [(text, line, _)] = faults(events)
    assert text.startswith("Index out of bounds") and line_text in text and "3 x 2" in text
    assert line == 3 and said(events) == ["1"] and model.program is None


def test_writing_outside_the_matrix_is_the_same_error() -> None:
    _, events = run_script(ROWS + "m[1, 5] = 0\n")
    [(text, line, _)] = faults(events)
    assert text.startswith("Index out of bounds") and line == 2


def test_two_indices_need_a_matrix() -> None:
    _, events = run_script("a = [1, 2, 3]\nx = a[0, 1]\n")
    [(text, line, _)] = faults(events)
    assert "Type error" in text and "matrix" in text and line == 2


def test_an_index_must_be_an_int() -> None:
    _, events = run_script(ROWS + "x = m[0, 1.5]\n")
    [(text, _, _)] = faults(events)
    assert "an index must be an int" in text


def test_products_as_the_manual_defines_them() -> None:
    _, events = run_script(
        "textmsg([[1, 2], [3, 4], [5, 6]] * [[10, 20, 30], [40, 50, 60]])\n"  # 3x2 times 2x3
        "textmsg([[1, 2], [3, 4], [5, 6]] * [10, 20])\n"  # a matrix times an array: an array
        "textmsg(5 * [[1, 2], [3, 4]])\ntextmsg([[10, 20]] / 10)\n"  # a number: every entry
    )
    assert said(events) == [
        "[[90, 120, 150], [190, 260, 330], [290, 400, 510]]",
        "[50, 110, 170]",
        "[[5, 10], [15, 20]]",
        "[[1, 2]]",
    ] and not faults(events)


def test_a_product_of_shapes_that_do_not_fit_is_a_type_error() -> None:
    _, events = run_script("x = [[1, 2], [3, 4]] * [[1, 2, 3]]\n")
    [(text, line, _)] = faults(events)
    assert "Type error" in text and "2 x 2" in text and "1 x 3" in text and line == 1


def test_transpose_and_inv() -> None:
    _, events = run_script(
        "textmsg(transpose([[1, 2, 3], [4, 5, 6]]))\n"
        "textmsg(inv([[0, 1, 0], [0, 0, 1], [1, 0, 0]]))\n"  # the Script Manual's example
        "x = inv([[1, 2], [2, 4]])\n"
    )
    assert said(events)[:2] == ["[[1, 4], [2, 5], [3, 6]]", "[[0, 0, 1], [1, 0, 0], [0, 1, 0]]"]
    [(text, line, _)] = faults(events)
    assert "singular" in text and line == 3


def test_transpose_makes_an_array_a_column_and_a_column_an_array() -> None:
    """The Script Directory's examples: transpose([1,2,3]) is [[1],[2],[3]], transpose of that
    is [1,2,3]; a row matrix still becomes a column matrix."""
    _, events = run_script(
        "textmsg(transpose([1, 2, 3]), transpose([[1], [2], [3]]))\ntextmsg(transpose([[1, 2]]))\n"
    )
    assert said(events) == ["[[1], [2], [3]][1, 2, 3]", "[[1], [2]]"] and not faults(events)


def test_inv_of_a_pose_is_the_inverse_transformation() -> None:
    _, events = run_script(
        "x = inv(p[.2, .5, .1, 1.57, 0, 3.14])\ntextmsg([x[0], x[1], x[2], x[3], x[4], x[5]])\n"
        "textmsg(x == pose_inv(p[.2, .5, .1, 1.57, 0, 3.14]))\n"
    )
    [numbers, same] = said(events)
    manual = [0.19324, 0.41794, -0.29662, 1.23993, 0.0, 2.47985]  # the Script Manual's example
    assert [float(v) for v in numbers.strip("[]").split(",")] == pytest.approx(manual, abs=1e-5)
    assert same == "True"


def test_a_subscript_pair_parses_where_one_subscript_does() -> None:
    script = parse("m[1, 0] = m[0, 1] + q[2]\n")
    [stmt] = script.main
    assert stmt.kind == "assign" and stmt.name == "m"
    [pair] = stmt.index
    assert pair.kind == "pair" and [e.value for e in pair.items] == [1, 0]
    assert stmt.expr is not None and stmt.expr.items[0].kind == "index"
    assert [e.value for e in stmt.expr.items[0].items[1:]] == [0, 1]
    with pytest.raises(ScriptFault, match="syntax_error_on_line:1"):
        parse("x = m[1, 2, 3]\n")  # a matrix has two indices
    with pytest.raises(ScriptFault, match="syntax_error_on_line:1"):
        parse("x = m[]\n")


def test_a_variable_named_p_is_a_matrix_like_any_other() -> None:
    _, events = run_script("p = [[1, 2], [3, 4]]\ntextmsg(p[1, 0])\np[0, 1] = 7\ntextmsg(p)\n")
    assert said(events) == ["3", "[[1, 7], [3, 4]]"] and not faults(events)


def test_int_products_are_exact_and_32_bit_and_no_bigger_than_a_value() -> None:
    _, events = run_script("textmsg([[70000, -3]] * [-30000, 7])\nx = [[65536]] * [[65536]]\n")
    assert said(events) == ["[-2100000021]"]
    [(text, line, _)] = faults(events)
    assert text.startswith("Integer overflow") and line == 2
    row = "[" + ", ".join(["1"] * 300) + "]"
    _, events = run_script(f"c = [{row}]\nr = transpose(c)\nx = r * c\n")
    [(text, line, _)] = faults(events)
    assert "a product of 300 x 300 entries" in text and line == 3
