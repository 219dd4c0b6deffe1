"""The field catalogue: completeness against the guides, types, and availability by version."""

from __future__ import annotations

import pytest

from rtde_spec.metamodel.catalogue import Catalogue

from .helpers import DATA

CAT = Catalogue.builtin()


def _guide_fields() -> list[tuple[str, str]]:
    lines = (DATA / "guide_fields.txt").read_text().splitlines()
    return [tuple(line.split()) for line in lines if line and not line.startswith("#")]  # type: ignore[misc]


@pytest.mark.parametrize("direction,name", _guide_fields())
def test_every_guide_field_is_in_the_spec(direction: str, name: str) -> None:
    entries = CAT.spec.fields.inputs if direction == "input" else CAT.spec.fields.outputs
    assert name in {e.name for e in entries}


@pytest.mark.parametrize(
    "direction,name,type_",
    [
        ("output", "control_step", "UINT64"),
        ("output", "target_base_wrench", "VECTOR6D"),
        ("input", "tool_digital_output_mask", "UINT8"),
        ("input", "tool_digital_output", "UINT8"),
    ],
)
def test_fields_of_other_implementations(direction: str, name: str, type_: str) -> None:
    info = CAT.get(name, direction)  # type: ignore[arg-type]
    assert info is not None and info.type == type_ and "third-party" in info.sources


def test_register_families_expand_to_concrete_names() -> None:
    outputs = CAT.names("output")
    inputs = CAT.names("input")
    assert [f"output_int_register_{i}" for i in range(48)] == [
        n for n in outputs if n.startswith("output_int_register_")
    ]
    assert "input_bit_register_64" in inputs and "input_bit_register_127" in inputs
    assert "input_bit_register_63" not in inputs
    # read-backs of the input registers are outputs too
    assert CAT.get("input_double_register_30", "output") is not None


@pytest.mark.parametrize(
    "name,direction,version,available",
    [
        ("safety_status", "output", "3.9.0", False),
        ("safety_status", "output", "3.10.0", True),
        ("safety_status", "output", "5.3.9", False),
        ("safety_status", "output", "5.4.0", True),
        ("output_int_register_24", "output", "3.8.0", False),
        ("output_int_register_24", "output", "3.9.0", True),
        ("output_int_register_23", "output", "3.4.0", True),
        ("output_int_register_23", "output", "3.3.0", False),
        ("input_int_register_30", "input", "5.2.0", False),
        ("input_int_register_30", "input", "5.3.0", True),
        ("actual_current_as_torque", "output", "5.22.0", False),
        ("actual_current_as_torque", "output", "5.23.0", True),
        ("actual_current_as_torque", "output", "10.10.0", False),
        ("actual_current_as_torque", "output", "10.11.0", True),
        ("ft_raw_wrench", "output", "3.15.8", False),
        ("ft_raw_wrench", "output", "5.9.0", True),
        ("time_scale_source", "output", "10.0.0", True),  # inherited from e-Series
        ("target_gravity", "output", "5.25.9", False),
        ("target_gravity", "output", "10.12.0", True),
        ("timestamp", "output", "3.3.0", True),
        ("timestamp", "output", "5.15.0.0", True),
    ],
)
def test_availability_by_version(name: str, direction: str, version: str, available: bool) -> None:
    info = CAT.get(name, direction)  # type: ignore[arg-type]
    assert info is not None
    assert CAT.available(info, version) is available


def test_wire_types_from_primitives() -> None:
    wt = CAT.wire_types
    assert (wt["VECTOR6D"].size, wt["VECTOR6D"].struct) == (48, "6d")
    assert (wt["VECTOR6INT32"].size, wt["VECTOR6INT32"].struct) == (24, "6i")
    assert wt["UINT8"].bounds == (0, 255)
    assert wt["INT32"].bounds == (-(2**31), 2**31 - 1)
    assert wt["BOOL"].size == 1 and wt["STRING"].size is None


def test_enums_and_bits_attached() -> None:
    assert CAT.get("robot_mode", "output").enum == "RobotMode"  # type: ignore[union-attr]
    assert CAT.get("joint_mode", "output").enum == "JointMode"  # type: ignore[union-attr]
    assert CAT.get("safety_status_bits", "output").bits == "SafetyStatusBits"  # type: ignore[union-attr]
    assert CAT.get("input_int_register_3", "input").reserved  # type: ignore[union-attr]
    assert not CAT.get("input_int_register_24", "input").reserved  # type: ignore[union-attr]


def test_unknown_controller_line_is_a_clear_error() -> None:
    from rtde_spec.errors import RecipeError

    with pytest.raises(RecipeError, match="no known product line"):
        CAT.line_of("4.1.0")
    with pytest.raises(RecipeError, match="bad version string"):
        CAT.line_of("five")


def test_a_direction_that_is_none_is_a_usage_error() -> None:
    """Catalogue.get/fields/names and RecipeCodec.for_names with "outputs" raised KeyError."""
    from rtde_spec import RecipeCodec
    from rtde_spec.errors import UsageError

    cat = Catalogue.default()
    calls = (
        lambda: cat.get("timestamp", "outputs"),  # type: ignore[arg-type]
        lambda: cat.fields("outputs"),  # type: ignore[arg-type]
        lambda: cat.names("outputs"),  # type: ignore[arg-type]
        lambda: RecipeCodec.for_names(["timestamp"], "outputs"),  # type: ignore[arg-type]
    )
    for call in calls:
        with pytest.raises(UsageError, match="direction must be input or output, not 'outputs'"):
            call()
    assert cat.get("timestamp", "output") is not None and cat.get("nope", "input") is None
