"""The compiled recipe codec: round trips of random recipes drawn from the spec, range
errors that name the field, size checks, bulk decode and tables."""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtde_spec.errors import DecodeError, EncodeError, RecipeError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.output.tables import to_arrow, to_pandas
from rtde_spec.recipes.codec import RecipeCodec
from tests.budget import examples

from .strategies import wire_value

CAT = Catalogue.builtin()


@st.composite
def recipe_and_values(draw: st.DrawFn, allow_nan: bool = False) -> tuple[RecipeCodec, dict]:
    direction = draw(st.sampled_from(["input", "output"]))
    names = CAT.names(direction)
    chosen = draw(st.lists(st.sampled_from(names), min_size=1, max_size=25, unique=True))
    codec = RecipeCodec.for_names(chosen, direction, CAT)  # type: ignore[arg-type]
    values = {item.name: draw(wire_value(item.wire, allow_nan)) for item in codec.items}
    return codec, values


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, (list, tuple)):
        return all(_same(x, y) for x, y in zip(a, b, strict=True))  # type: ignore[arg-type]
    return a == b


@settings(max_examples=examples(200), deadline=None)
@given(recipe_and_values())
def test_round_trip_dict_record_model_package(case: tuple[RecipeCodec, dict]) -> None:
    codec, values = case
    payload = codec.encode(values, strict=True)
    assert len(payload) == codec.size == sum(i.wire.size or 0 for i in codec.items)
    assert codec.decode(payload) == values
    record = codec.decode_record(payload)
    assert record._asdict() == values
    assert codec.encode(record) == payload
    model = codec.decode_model(payload)
    assert codec.encode(model) == payload
    package = codec.encode_package(values, recipe_id=7)
    assert int.from_bytes(package[:2], "big") == len(package)
    assert codec.decode_package(package, recipe_id=7) == record


@settings(max_examples=examples(100), deadline=None)
@given(recipe_and_values(allow_nan=True), st.integers(1, 20))
def test_bulk_decode_matches_per_packet(case: tuple[RecipeCodec, dict], count: int) -> None:
    codec, values = case
    package = codec.encode_package(values, recipe_id=3)
    arr = codec.decode_many(package * count, recipe_id=3)
    assert arr.shape == (count,)
    for item in codec.items:
        column = arr[item.name]
        expected = values[item.name]
        if item.wire.count > 1:
            assert column.shape == (count, item.wire.count)
            assert _same(list(column[-1]), list(expected))
        else:
            assert _same(column[0].item(), expected)


@settings(max_examples=examples(100), deadline=None)
@given(recipe_and_values(), st.integers(0, 12), st.integers(0, 11))
def test_records_of_many_packages_are_those_of_each(
    case: tuple[RecipeCodec, dict], count: int, bad: int
) -> None:
    """decode_records (one C loop) gives what decode_package gives per package, and names a
    bad package by its place as decode_package would."""
    codec, values = case
    package = codec.encode_package(values, recipe_id=9)
    data = package * count
    records = codec.decode_records(data, recipe_id=9)
    assert records == [codec.decode_package(package, recipe_id=9)] * count
    assert all(type(r) is codec.record_type for r in records)
    if bad < count:
        broken = bytearray(data)
        broken[bad * len(package) + 2] ^= 0xFF  # its type
        with pytest.raises(DecodeError) as info:
            codec.decode_records(bytes(broken))
        assert info.value.offset == bad * len(package) + 2 and f"#{bad}" in str(info.value)
        with pytest.raises(DecodeError, match="another recipe"):
            codec.decode_records(data, recipe_id=8)
    with pytest.raises(DecodeError, match="whole number"):
        codec.decode_records(data + b"\0")


def test_uint8_out_of_range_names_field_and_bounds() -> None:
    codec = RecipeCodec.for_names(["standard_digital_output_mask", "speed_slider_fraction"], "input")
    with pytest.raises(EncodeError) as info:
        codec.encode({"standard_digital_output_mask": 300, "speed_slider_fraction": 0.5})
    err = info.value
    assert (err.field, err.expected, err.actual) == ("standard_digital_output_mask", "0..255", "300")


def test_vector_element_out_of_range_and_wrong_length() -> None:
    codec = RecipeCodec.for_names(["joint_mode"], "output")
    with pytest.raises(EncodeError) as info:
        codec.encode({"joint_mode": (0, 0, 0, 2**31, 0, 0)})
    assert info.value.field == "joint_mode[3]"
    with pytest.raises(EncodeError, match="exactly 6 values"):
        codec.encode({"joint_mode": (0, 0, 0)})


def test_strict_bool_rejects_non_bool() -> None:
    codec = RecipeCodec.for_names(["input_bit_register_64"], "input")
    assert codec.encode({"input_bit_register_64": 1}) == b"\x01"
    with pytest.raises(EncodeError, match="not a bool"):
        codec.encode({"input_bit_register_64": 1}, strict=True)
    with pytest.raises(EncodeError):
        codec.encode({"input_bit_register_64": "yes"})


def test_missing_and_extra_values() -> None:
    codec = RecipeCodec.for_names(["timestamp"], "output")
    with pytest.raises(EncodeError, match="missing value"):
        codec.encode({})
    with pytest.raises(EncodeError, match="not in the recipe: actual_q"):
        codec.encode({"timestamp": 1.0, "actual_q": (0,) * 6})


def test_short_payload_names_the_field_it_cuts() -> None:
    codec = RecipeCodec.for_names(["timestamp", "actual_q", "robot_mode"], "output")
    payload = codec.encode({"timestamp": 1.0, "actual_q": (0.0,) * 6, "robot_mode": 7})
    with pytest.raises(DecodeError) as info:
        codec.decode(payload[:30])
    assert (info.value.field, info.value.offset) == ("actual_q", 8)  # offsets count from the bytes given
    with pytest.raises(DecodeError, match="longer"):
        codec.decode_record(payload + b"\0")


@pytest.mark.parametrize("given", [[1, 2], {"timestamp": [1.0]}, None, np.zeros(3)])
def test_tables_of_what_is_no_structured_array_are_a_usage_error(given: object) -> None:
    """A list, dict or plain array raised AttributeError ('list' has no 'dtype') or TypeError."""
    from rtde_spec.errors import UsageError

    for convert in (to_pandas, to_arrow):
        with pytest.raises(UsageError, match=r"take the structured array RecipeCodec\.decode_many returns"):
            convert(given)


@pytest.mark.parametrize(("cut", "offset"), [(-4, -4), (0, -61), (0, 62), (10, -10)])
def test_an_offset_outside_the_bytes_is_named(cut: int, offset: int) -> None:
    """A negative offset raised a bare struct.error, or an error about the payload's length at a
    made-up place; past the end, "got -935 payload bytes"."""
    codec = RecipeCodec.for_names(["timestamp", "actual_q", "robot_mode"], "output")
    payload = bytes(codec.size + cut)
    for decoder in (codec.decode, codec.decode_record, codec.decode_model):
        with pytest.raises(DecodeError, match="offset outside the bytes given") as info:
            decoder(payload, offset)
        assert (info.value.expected, info.value.actual) == (f"0..{len(payload)}", offset)


def test_package_checks() -> None:
    codec = RecipeCodec.for_names(["timestamp"], "output")
    package = codec.encode_package({"timestamp": 2.0}, recipe_id=1)
    with pytest.raises(DecodeError, match="another recipe"):
        codec.decode_package(package, recipe_id=2)
    with pytest.raises(DecodeError, match="not a data package"):
        codec.decode_package(package[:2] + b"M" + package[3:])
    bad = package * 3
    bad = bad[: len(package) + 3] + b"\x09" + bad[len(package) + 4 :]
    with pytest.raises(DecodeError) as info:
        codec.decode_many(bad, recipe_id=1)
    assert info.value.offset == len(package) and "package 1" in str(info.value)
    with pytest.raises(DecodeError, match="whole number"):
        codec.decode_many(package + b"\0")


@pytest.mark.parametrize("gap", [0, 5, 40])
def test_bulk_decode_of_spaced_rows_as_a_capture_file_holds_them(gap: int) -> None:
    """Rows of packages with other bytes between them (frame headers in a capture) decode in
    place as they do back to back; a bad row is named by its place in the buffer."""
    codec = RecipeCodec.for_names(["timestamp", "actual_q", "robot_mode"], "output")
    packages = [
        codec.encode_package({"timestamp": i / 2, "actual_q": (i,) * 6, "robot_mode": i}, 1) for i in range(7)
    ]
    size = codec.package_size
    spaced = b"".join(b"\xee" * gap + p for p in packages)
    rows = np.ndarray((7, size), np.uint8, buffer=spaced, offset=gap, strides=(size + gap, 1))
    arr = codec.decode_many(rows, recipe_id=1)
    assert np.array_equal(arr, codec.decode_many(b"".join(packages)))
    assert arr["actual_q"][3].tolist() == [3.0] * 6 and arr["robot_mode"].tolist() == list(range(7))
    broken = bytearray(spaced)
    broken[gap + 4 * (size + gap) + 2] = ord("M")  # package 4 is not a data package
    rows = np.ndarray((7, size), np.uint8, buffer=bytes(broken), offset=gap, strides=(size + gap, 1))
    with pytest.raises(DecodeError) as info:
        codec.decode_many(rows)
    assert "package 4" in str(info.value) and info.value.offset == 4 * (size + gap)
    with pytest.raises(DecodeError, match="rows of"):
        codec.decode_many(np.zeros((2, size + 1), np.uint8))
    assert len(codec.decode_many(np.zeros((0, size), np.uint8))) == 0


@pytest.mark.parametrize("recipe_id", [300, -1, "1", 1.0])
def test_a_recipe_id_no_package_carries_is_named_by_every_decoder(recipe_id: object) -> None:
    """decode_many raised a bare struct.error for a recipe id outside 0..255 or no integer, and
    decode_package said "of another recipe (expected 1, got 1)" for the text '1'."""
    codec = RecipeCodec.for_names(["timestamp"], "output")
    package = codec.encode_package({"timestamp": 2.0}, recipe_id=1)
    for decoder in (codec.decode_many, codec.decode_records, codec.decode_package):
        if decoder is not codec.decode_many and recipe_id == 1:
            continue  # an integral float finds recipe 1, as 1 == 1.0
        with pytest.raises(DecodeError, match="no data package carries this recipe id") as info:
            decoder(package, recipe_id=recipe_id)
        assert (info.value.field, info.value.actual) == ("recipe_id", repr(recipe_id))


def test_rows_of_a_transposed_array_decode_as_the_rows_they_show() -> None:
    """A 2-D array whose rows are not contiguous (a transpose) raised numpy's ValueError."""
    codec = RecipeCodec.for_names(["timestamp"], "output")
    packages = b"".join(codec.encode_package({"timestamp": float(i)}, 1) for i in range(3))
    rows = np.asfortranarray(np.frombuffer(packages, np.uint8).reshape(3, -1))
    assert codec.decode_many(rows, recipe_id=1)["timestamp"].tolist() == [0.0, 1.0, 2.0]


def test_recipe_errors() -> None:
    with pytest.raises(RecipeError, match="unknown output field"):
        RecipeCodec.for_names(["nope"], "output")
    with pytest.raises(RecipeError, match="at least one"):
        RecipeCodec.for_names([], "output")
    with pytest.raises(RecipeError, match="twice"):
        RecipeCodec.for_names(["timestamp", "timestamp"], "output")
    with pytest.raises(RecipeError, match="no data layout"):
        RecipeCodec.for_types(["x"], ["NOT_FOUND"])


def test_tables() -> None:
    codec = RecipeCodec.for_names(["timestamp", "actual_q", "robot_mode"], "output")
    rows = [
        codec.encode_package({"timestamp": float(i), "actual_q": (i,) * 6, "robot_mode": i}, 1)
        for i in range(5)
    ]
    arr = codec.decode_many(b"".join(rows))
    assert arr.dtype["timestamp"].byteorder == ">"
    df = to_pandas(arr)
    assert list(df.columns) == ["recipe_id", "timestamp"] + [f"actual_q_{i}" for i in range(6)] + [
        "robot_mode"
    ]
    assert df["actual_q_5"].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
    table = to_arrow(arr)
    assert table.column("actual_q").to_pylist()[2] == [2.0] * 6
    assert table.column("robot_mode").to_pylist() == [0, 1, 2, 3, 4]
    assert np.array_equal(df["robot_mode"].to_numpy(), np.arange(5))


# --- strict encoding: the compiled path refuses what the per-value checks refuse -------------

STRICT = RecipeCodec.for_names(
    [
        "standard_digital_output_mask",  # UINT8
        "input_int_register_24",  # INT32
        "input_bit_register_64",  # BOOL
        "input_double_register_24",  # DOUBLE
        "configurable_digital_output",  # UINT8
    ],
    "input",
)
OUT = RecipeCodec.for_names(["timestamp", "actual_q", "joint_mode", "output_int_register_0"], "output")
GOOD = {
    "standard_digital_output_mask": 3,
    "input_int_register_24": -5,
    "input_bit_register_64": True,
    "input_double_register_24": 0.5,
    "configurable_digital_output": 255,
}
GOOD_OUT = {"timestamp": 1.5, "actual_q": (0.0,) * 6, "joint_mode": [253] * 6, "output_int_register_0": 0}


def _strict_error(codec: RecipeCodec, values: dict) -> EncodeError:
    """The error of both entries (payload and package), which must agree."""
    with pytest.raises(EncodeError) as payload_info:
        codec.encode(values, strict=True)
    with pytest.raises(EncodeError) as package_info:
        codec.encode_package(values, recipe_id=1, strict=True)
    assert str(payload_info.value) == str(package_info.value)
    return payload_info.value


@pytest.mark.parametrize(
    ("codec", "good", "field", "value", "reason", "expected"),
    [
        (STRICT, GOOD, "standard_digital_output_mask", 256, "out of range for UINT8", "0..255"),
        (STRICT, GOOD, "configurable_digital_output", -1, "out of range for UINT8", "0..255"),
        (STRICT, GOOD, "input_int_register_24", 2**31, "out of range for INT32", "-2147483648..2147483647"),
        (STRICT, GOOD, "input_int_register_24", -(2**31) - 1, "out of range for INT32", None),
        (STRICT, GOOD, "input_int_register_24", 1.0, "not an integer for INT32", "INT32"),
        (STRICT, GOOD, "input_int_register_24", True, "not an integer for INT32", "INT32"),
        (STRICT, GOOD, "standard_digital_output_mask", "3", "not an integer for UINT8", "UINT8"),
        (STRICT, GOOD, "input_bit_register_64", 1, "not a bool", "True or False"),
        (STRICT, GOOD, "input_bit_register_64", 1.0, "not a bool", "True or False"),
        (STRICT, GOOD, "input_double_register_24", True, "not a number for DOUBLE", "DOUBLE"),
        (STRICT, GOOD, "input_double_register_24", "0.5", "not a number for DOUBLE", "DOUBLE"),
        (STRICT, GOOD, "input_double_register_24", None, "not a number for DOUBLE", "DOUBLE"),
        (STRICT, GOOD, "input_double_register_24", 10**400, "out of range for DOUBLE", None),
        (OUT, GOOD_OUT, "output_int_register_0", -(2**31) - 1, "out of range for INT32", None),
        (OUT, GOOD_OUT, "timestamp", False, "not a number for DOUBLE", "DOUBLE"),
    ],
)
def test_strict_refusals_name_field_limit_and_value(
    codec: RecipeCodec, good: dict, field: str, value: object, reason: str, expected: str | None
) -> None:
    assert codec.encode(good, strict=True) == codec.encode(good)
    err = _strict_error(codec, {**good, field: value})
    assert (err.field, err.actual) == (field, repr(value))
    assert reason in str(err) and field in str(err) and repr(value) in str(err)
    if expected is not None:
        assert err.expected == expected


@pytest.mark.parametrize(
    ("field", "value", "bad_field", "reason"),
    [
        ("joint_mode", (0, 0, 0, 2**31, 0, 0), "joint_mode[3]", "out of range for VECTOR6INT32"),
        ("joint_mode", (0, 0, -(2**31) - 1, 0, 0, 0), "joint_mode[2]", "out of range for VECTOR6INT32"),
        ("joint_mode", (0, 0, 0, 0, 0, 1.5), "joint_mode[5]", "not an integer for VECTOR6INT32"),
        ("joint_mode", (0, 0, True, 0, 0, 0), "joint_mode[2]", "not an integer for VECTOR6INT32"),
        ("actual_q", (0.0, 0.0, 0.0, 0.0, 0.0, True), "actual_q[5]", "not a number for VECTOR6D"),
        ("actual_q", (0.0,) * 5, "actual_q", "exactly 6 values"),
        ("actual_q", (0.0,) * 7, "actual_q", "exactly 6 values"),
        ("actual_q", {0.0, 1.0, 2.0, 3.0, 4.0, 5.0}, "actual_q", "exactly 6 values"),  # unordered
        ("actual_q", "abcdef", "actual_q", "exactly 6 values"),
        ("actual_q", 0.0, "actual_q", "exactly 6 values"),
    ],
)
def test_strict_vector_refusals(field: str, value: object, bad_field: str, reason: str) -> None:
    err = _strict_error(OUT, {**GOOD_OUT, field: value})
    assert err.field == bad_field and reason in str(err)


@pytest.mark.parametrize(
    ("field", "value", "plain", "said"),
    [
        ("input_int_register_24", np.int32(7), 7, "a Python int for INT32, not numpy.int32"),
        ("standard_digital_output_mask", np.uint8(3), 3, "a Python int for UINT8, not numpy.uint8"),
        (
            "input_double_register_24",
            np.float32(0.5),
            0.5,
            "a Python int or float for DOUBLE, not numpy.float32",
        ),
        (
            "input_double_register_24",
            Fraction(1, 2),
            0.5,
            "a Python int or float for DOUBLE, not fractions.Fraction",
        ),
    ],
)
def test_strict_says_it_refuses_the_type_of_a_number(
    field: str, value: object, plain: object, said: str
) -> None:
    """Strict mode refused np.int32(7) as "not an integer for INT32" and np.float32 as "not a
    number": both are; what strict refuses is their type."""
    err = _strict_error(STRICT, {**GOOD, field: value})
    assert f"strict mode takes {said}" in str(err) and err.field == field
    assert STRICT.encode({**GOOD, field: value}) == STRICT.encode({**GOOD, field: plain})


def test_strict_negative_uint32_names_its_limits() -> None:
    codec = RecipeCodec.for_names(["robot_status_bits"], "output")
    assert codec.items[0].wire.name == "UINT32"
    err = _strict_error(codec, {"robot_status_bits": -1})
    assert (err.field, err.expected, err.actual) == ("robot_status_bits", "0..4294967295", "-1")


def test_strict_takes_what_the_spec_allows() -> None:
    """Ints for doubles, lists for vectors, IEEE specials (the spec sets no range for DOUBLE),
    int subclasses (an IntEnum) for integers: the same bytes as the non-strict path."""
    import enum

    class Mode(enum.IntEnum):
        RUNNING = 253

    values = {
        "timestamp": 1,
        "actual_q": [math.nan, math.inf, -math.inf, -0.0, 1, 2**60],
        "joint_mode": (Mode.RUNNING,) * 6,
        "output_int_register_0": -(2**31),
    }
    payload = OUT.encode(values, strict=True)
    assert payload == OUT.encode(values)
    decoded = OUT.decode(payload)
    assert decoded["joint_mode"] == (253,) * 6 and decoded["timestamp"] == 1.0
    assert _same(list(decoded["actual_q"]), [math.nan, math.inf, -math.inf, -0.0, 1.0, float(2**60)])


@st.composite
def mixed_values(draw: st.DrawFn) -> tuple[RecipeCodec, dict]:
    """Values of every Python type a caller might pass, right or wrong, for a random recipe."""
    codec, values = draw(recipe_and_values())
    odd = st.one_of(
        st.booleans(),
        st.integers(-(2**65), 2**65),
        st.floats(allow_nan=True),
        st.none(),
        st.text(max_size=2),
    )
    numpy_scalar = st.sampled_from([np.float64, np.float32, np.int64, np.uint8, np.bool_])
    for name in draw(st.lists(st.sampled_from(list(values)), max_size=3, unique=True)):
        value = values[name]
        if isinstance(value, tuple) and draw(st.booleans()):
            items = list(value)
            items[draw(st.integers(0, len(items) - 1))] = draw(odd)
            values[name] = draw(st.sampled_from([tuple, list]))(items)
        elif isinstance(value, tuple) and draw(st.booleans()):  # the right length, another container
            values[name] = draw(st.sampled_from(VECTOR_CONTAINERS))(value)
        elif draw(st.booleans()) and not isinstance(value, tuple):  # the right value, a numpy scalar
            values[name] = _as_numpy(draw(numpy_scalar), value)
        else:
            values[name] = draw(odd)
    return codec, values


def _as_numpy(kind: type, value: object) -> object:
    """`value` as a numpy scalar of `kind` (cast as numpy casts), or itself where numpy refuses."""
    try:
        with np.errstate(all="ignore"):
            return kind(value)
    except (OverflowError, ValueError, TypeError):
        return value


VECTOR_CONTAINERS = [
    np.array,
    lambda v: np.array([v]),  # 2-D
    set,
    dict.fromkeys,
    lambda v: bytes(x % 256 for x in v) if all(type(x) is int for x in v) else list(v),
    lambda v: "".join(map(str, v)),
    lambda v: iter(v),  # no length
    lambda v: {x: 0 for x in v}.keys(),
]


@settings(max_examples=examples(300), deadline=None)
@given(mixed_values(), st.booleans())
def test_compiled_path_agrees_with_the_per_value_checks(case: tuple[RecipeCodec, dict], strict: bool) -> None:
    """A dict takes the compiled one-call path, a read-only mapping the per-value checks: the
    same bytes from both, or EncodeError from both, naming the same field."""
    from types import MappingProxyType

    codec, values = case
    outcomes = []
    for given_values in (values, MappingProxyType(values)):
        try:
            outcomes.append(codec.encode_package(given_values, recipe_id=5, strict=strict))
        except EncodeError as exc:
            outcomes.append(("error", exc.field))
    assert outcomes[0] == outcomes[1]


@pytest.mark.parametrize("strict", [False, True])
@pytest.mark.parametrize(
    ("value", "reason"),
    [
        (dict.fromkeys((0.0, 1.0, 2.0, 3.0, 4.0, 5.0)), "a mapping would send its keys"),
        ({0.0, 1.0, 2.0, 3.0, 4.0, 5.0}, "a set has no order"),
        (frozenset({0.0, 1.0, 2.0, 3.0, 4.0, 5.0}), "a set has no order"),
        (dict.fromkeys((0.0, 1.0, 2.0, 3.0, 4.0, 5.0)).keys(), "a set has no order"),
        (b"abcdef", "text or bytes"),
        (bytearray(b"abcdef"), "text or bytes"),
        ("012345", "text or bytes"),
        (np.zeros((6, 1)), "an array of 2 dimensions"),
        (np.zeros((1, 6)), "an array of 2 dimensions"),
        (iter([0.0] * 6), "not a list, tuple or 1-D array"),
        (np.zeros(5), "5 given"),
    ],
)
def test_what_unpacks_but_is_no_vector_is_refused_in_both_modes(
    value: object, reason: str, strict: bool
) -> None:
    """A dict, set, string or bytes of the right length unpacks: the default mode sent a
    dict's keys, a set's values in hash order and bytes as character codes."""
    with pytest.raises(EncodeError) as info:
        OUT.encode_package({**GOOD_OUT, "actual_q": value}, recipe_id=1, strict=strict)
    assert info.value.field == "actual_q"
    assert reason in str(info.value) and "needs exactly 6 values" in str(info.value)


def test_numpy_vectors_and_scalars_encode_as_their_values_and_errors_name_the_bad_field() -> None:
    """A 1-D numpy array is a vector and numpy scalars are numbers, as `struct` takes them;
    a bad value elsewhere is named, not the array (the per-value checks refused any array)."""
    import array
    from decimal import Decimal
    from fractions import Fraction
    from types import MappingProxyType

    plain = OUT.encode(GOOD_OUT)
    given = {
        "timestamp": np.float32(1.5),
        "actual_q": np.zeros(6),
        "joint_mode": np.full(6, 253, dtype=np.int32),
        "output_int_register_0": np.int64(0),
    }
    others = {
        "timestamp": Fraction(3, 2),
        "actual_q": array.array("d", [0.0] * 6),
        "joint_mode": [np.uint8(253)] * 6,
        "output_int_register_0": np.float64(0.0),  # an integral float, as for a plain float
    }
    for values in (given, others, {**GOOD_OUT, "timestamp": Decimal("1.5")}):
        for container in (dict, MappingProxyType):  # the one-call path, the per-value checks
            assert OUT.encode(container(values)) == plain
    with pytest.raises(EncodeError) as info:
        OUT.encode({**given, "output_int_register_0": np.int64(2**40)})
    assert info.value.field == "output_int_register_0" and "out of range for INT32" in str(info.value)
    for one_value_array in (np.array([3]), np.array([3.0])):  # __index__ or __float__, refused by both
        with pytest.raises(EncodeError) as info:
            OUT.encode({**given, "output_int_register_0": one_value_array})
        assert info.value.field == "output_int_register_0" and "not an integer" in str(info.value)
    with pytest.raises(EncodeError) as info:
        OUT.encode({**given, "output_int_register_0": 2.5})
    assert info.value.field == "output_int_register_0" and "not an integer" in str(info.value)
    bits = RecipeCodec.for_names(["input_bit_register_64"], "input")
    numpy_true = bits.encode({"input_bit_register_64": np.bool_(True)})
    assert numpy_true == bits.encode({"input_bit_register_64": True})
    with pytest.raises(EncodeError, match="not a bool"):
        bits.encode({"input_bit_register_64": np.bool_(True)}, strict=True)
    for not_a_bool in (np.int64(2), np.array([1]), "1"):
        with pytest.raises(EncodeError, match="not a bool"):
            bits.encode({"input_bit_register_64": not_a_bool})


def assert_one_call_path(codec: RecipeCodec, values: dict[str, object]) -> None:
    """Both modes encode `values` without falling back to the value-by-value checks."""
    scope = codec.encode_package.__globals__  # the generated function's own namespace
    explained = scope["slow"]

    def refused(*args: object) -> bytes:
        raise AssertionError(f"the one-call path refused {args[1:]}")

    scope["slow"] = refused
    try:
        assert codec.encode_package(values, 1, strict=True) == codec.encode_package(values, 1)
    finally:
        scope["slow"] = explained
    assert codec.encode_package(values, 1) == explained(values, 1, False)


def test_strict_costs_about_what_the_default_mode_costs() -> None:
    """Strict checks are compiled into the one-call path: on ur_rtde's 58-field recipe strict
    took 12-21x the default mode when it went value by value; now about 2x (4x allowed for a
    loaded machine).

    Timed in this thread's CPU time, in short rounds in turn, the fastest of each mode: a
    round of wall time also held what other threads of the worker (a server an earlier test
    left winding down) and other processes ran meanwhile, which once made strict's longer
    rounds 4.4x the default's in every round of a run beside a CPU hog.
    """
    import time
    from importlib import resources

    text = resources.files("rtde_spec.examples").joinpath("ur_rtde_default_outputs.txt").read_text()
    names = [line.strip() for line in text.splitlines() if line.strip() and not line.startswith("#")]
    codec = RecipeCodec.for_names(names, "output")
    assert len(codec.items) == 58
    values = {
        item.name: {"float": 0.5, "int": 1, "bool": True}[item.wire.kind]
        if item.wire.count == 1
        else ({"float": 0.5, "int": 1, "bool": True}[item.wire.kind],) * item.wire.count
        for item in codec.items
    }
    # the one-call path itself takes these values in both modes (a refusal would fall back,
    # value by value, to the slow path and still give the same bytes)
    assert_one_call_path(codec, values)

    def per_call(strict: bool) -> float:
        start = time.thread_time_ns()
        for _ in range(100):
            codec.encode_package(values, recipe_id=1, strict=strict)
        return (time.thread_time_ns() - start) / 100

    rounds = [(per_call(True), per_call(False)) for _ in range(40)]
    strict, default = (min(times) for times in zip(*rounds, strict=True))  # the least disturbed
    assert strict / default < 4.0, (strict, default, rounds)


def test_the_generated_methods_keep_the_public_signature_and_docstring() -> None:
    """encode and encode_package are generated per codec (one frame per call): callers keep
    the keyword names, help() keeps the docstring, and every input form still works."""
    import inspect

    codec = RecipeCodec.for_names(["target_q", "output_int_register_0", "output_bit_register_70"], "output")
    values = {"target_q": [0.5] * 6, "output_int_register_0": 7, "output_bit_register_70": True}
    for name in ("encode", "encode_package"):
        generated, method = getattr(codec, name), getattr(RecipeCodec, name)
        assert generated.__doc__ == method.__doc__ and generated.__name__ == name
        assert list(inspect.signature(generated).parameters) == list(inspect.signature(method).parameters)[1:]
    package = codec.encode_package(values=values, recipe_id=3, strict=True)
    assert package == codec.encode_package(values, 3) == codec.encode_package(codec.decode(package[4:]), 3)
    assert codec.encode(values=values, strict=True) == package[4:]
    with pytest.raises(EncodeError, match="recipe id out of range"):
        codec.encode_package(values, recipe_id=256)


def test_the_one_call_path_takes_what_strict_mode_takes() -> None:
    """Ints for doubles and bools for BOOL are strict-valid: no value-by-value fallback; a bool
    for an integer is refused by both paths alike."""
    codec = RecipeCodec.for_names(["target_q", "output_int_register_0", "output_bit_register_70"], "output")
    assert_one_call_path(
        codec, {"target_q": [0, 1, 2, 3, 4, 5.5], "output_int_register_0": 7, "output_bit_register_70": False}
    )
    with pytest.raises(EncodeError, match="output_int_register_0"):
        codec.encode_package(
            {"target_q": [0.0] * 6, "output_int_register_0": True, "output_bit_register_70": False},
            1,
            strict=True,
        )


def test_a_subclass_that_overrides_encode_keeps_its_own() -> None:
    """The generated functions stand in for the methods only where the class does not override
    them: a subclass's own encode_package runs."""

    class Counting(RecipeCodec):
        calls = 0

        def encode_package(self, values: Any, recipe_id: int, strict: bool = False) -> bytes:
            Counting.calls += 1
            return super().encode_package(values, recipe_id, strict)

    codec = Counting.for_names(["output_int_register_0"], "output")
    assert isinstance(codec, Counting)
    package = codec.encode_package({"output_int_register_0": 5}, 1)
    assert Counting.calls == 1
    assert package == RecipeCodec.for_names(["output_int_register_0"], "output").encode_package(
        {"output_int_register_0": 5}, 1
    )
    assert codec.encode({"output_int_register_0": 5}) == package[4:]  # not overridden: generated
    assert "encode" in vars(codec) and "encode_package" not in vars(codec)
