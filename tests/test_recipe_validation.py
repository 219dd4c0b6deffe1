"""Every offline validation rule, one test each, plus the controller's answer."""

from __future__ import annotations

import pytest

from rtde_spec.errors import RecipeError, UsageError
from rtde_spec.recipes.model import Recipe
from rtde_spec.recipes.validation import (
    NOT_FOUND,
    controller_answer,
    validate_recipe,
    validate_recipes,
)

from .helpers import DATA


def codes(report: object) -> dict[str, list[str | None]]:
    out: dict[str, list[str | None]] = {}
    for p in report.all_problems if hasattr(report, "all_problems") else report.problems:  # type: ignore[attr-defined]
        out.setdefault(p.code, []).append(p.field)
    return out


def check(names: str, **kw: object) -> object:
    return validate_recipes([Recipe.parse(names)], **kw)  # type: ignore[arg-type]


def test_a_good_recipe_is_valid() -> None:
    report = check("timestamp,actual_q,robot_mode", controller="5.12.2", frequency=500)
    assert report.valid and not report.all_problems  # type: ignore[attr-defined]


def test_unknown_name_with_suggestions() -> None:
    report = check("timestamp,actual_qq", controller="5.12.2")
    (problem,) = report.all_problems  # type: ignore[attr-defined]
    assert (problem.code, problem.field, problem.severity) == ("unknown-name", "actual_qq", "error")
    assert "did you mean actual_q" in problem.message


def test_register_index_outside_its_family() -> None:
    report = check("output_int_register_48", controller="5.12.2")
    assert "outside output_int_register_{X} (0..47)" in report.all_problems[0].message  # type: ignore[attr-defined]


def test_wrong_direction() -> None:
    report = validate_recipes([Recipe(("timestamp", "speed_slider_mask"), direction="output")])
    assert codes(report) == {"wrong-direction": ["speed_slider_mask"]}
    assert "is an input, not an output" in report.all_problems[0].message


@pytest.mark.parametrize(
    "name,version,message",
    [
        ("safety_status", "3.9.0", "available from 3.10.0 on CB3"),
        ("safety_status", "5.3.0", "available from 5.4.0 on e-Series"),
        ("ft_raw_wrench", "3.15.8", "not available on CB3"),
        ("actual_current_as_torque", "10.10.0", "available from 10.11.0 on PolyScope X"),
    ],
)
def test_not_available_on_that_version(name: str, version: str, message: str) -> None:
    report = check(f"timestamp,{name}", controller=version)
    (problem,) = report.all_problems  # type: ignore[attr-defined]
    assert problem.code == "not-available" and message in problem.message
    assert report.recipes[0].answer == ["DOUBLE", NOT_FOUND]  # type: ignore[attr-defined]


def test_xml_type_disagreeing_with_the_spec() -> None:
    recipe = Recipe(("timestamp", "actual_q"), declared_types={"timestamp": "DOUBLE", "actual_q": "VECTOR3D"})
    report = validate_recipes([recipe], controller="5.12.2")
    assert codes(report) == {"type-mismatch": ["actual_q"]}
    assert "says VECTOR3D, the spec says VECTOR6D" in report.all_problems[0].message


def test_duplicates() -> None:
    report = check("timestamp,actual_q,timestamp")
    assert codes(report) == {"duplicate": ["timestamp"]}


def test_empty_output_recipe() -> None:
    report = validate_recipes([Recipe((), direction="output")])
    assert codes(report) == {"empty-recipe": [None]}
    assert "at least one output" in report.all_problems[0].message


def test_names_over_2048_bytes() -> None:
    names = [f"output_double_register_{i}" for i in range(48)] + [
        f"output_int_register_{i}" for i in range(48)
    ]
    names += [f"output_bit_register_{i}" for i in range(64, 128)]
    assert len(",".join(names)) > 2048
    report = validate_recipes([Recipe(tuple(names), direction="output")], controller="3.15.8")
    assert "names-too-long" in codes(report) and not report.valid
    assert "CB3" in next(p.message for p in report.all_problems if p.code == "names-too-long")
    # e-Series documents no such limit (URCL sets up 9,173 bytes against URSim 5.x): valid there
    eseries = validate_recipes([Recipe(tuple(names), direction="output")], controller="5.15.0")
    assert "names-too-long" not in codes(eseries) and eseries.valid


def test_urcl_sized_name_list_is_valid_on_e_series_only() -> None:
    names = [f"output_double_register_{i % 48}" for i in range(360)]
    assert 9173 <= len(",".join(names)) < 65532  # URCL's size, well within a setup package
    recipe = Recipe(tuple(names), direction="output")
    on_cb3 = validate_recipe(recipe, controller="3.15.8")
    on_e = validate_recipe(recipe, controller="5.15.0")
    assert "names-too-long" in codes(on_cb3)
    assert "names-too-long" not in codes(on_e)


@pytest.mark.parametrize(
    "version,freq,ok,divisor",
    [
        ("3.15.8", 125, True, 1),
        ("3.15.8", 126, False, None),
        ("3.15.8", 50, True, 2),
        ("5.12.2", 500, True, 1),
        ("5.12.2", 501, False, None),
        ("5.12.2", 0.5, False, None),
        ("5.12.2", 300, True, 1),
        ("10.11.0", 200, True, 2),
    ],
)
def test_frequency_range_and_effective_rate(version: str, freq: float, ok: bool, divisor: int | None) -> None:
    report = check("timestamp", controller=version, frequency=freq)
    assert report.valid is ok  # type: ignore[attr-defined]
    rec = report.recipes[0]  # type: ignore[attr-defined]
    assert rec.rate_divisor == divisor
    if divisor:
        top = 125 if version.startswith("3.") else 500
        assert rec.effective_frequency == top / divisor
    if not ok:
        assert "frequency-range" in codes(report)


def test_data_package_too_large_for_the_size_field() -> None:
    # within 2048 bytes of names no recipe reaches 64 KiB; past that limit both are reported
    report = validate_recipe(Recipe(("actual_q",) * 1400, direction="output"))
    found = codes(report)
    assert {"package-too-large", "names-too-long", "duplicate"} <= set(found)
    assert report.payload_bytes == 1400 * 48
    fits = validate_recipe(Recipe(("actual_q",) * 1300, direction="output"))
    assert "package-too-large" not in codes(fits)


def test_reserved_input_registers_are_warnings() -> None:
    report = validate_recipes(
        [
            Recipe(
                ("input_int_register_3", "input_bit_registers0_to_31", "input_int_register_24"),
                direction="input",
            )
        ],
        controller="5.12.2",
    )
    assert report.valid
    assert codes(report) == {"reserved": ["input_int_register_3", "input_bit_registers0_to_31"]}


def test_shared_input_across_recipes_is_reported_not_rejected() -> None:
    report = validate_recipes(
        [
            Recipe(("input_int_register_24", "input_double_register_24"), direction="input", key="a"),
            Recipe(("input_int_register_24",), direction="input", key="b"),
        ],
        controller="5.12.2",
    )
    assert report.valid
    (problem,) = report.problems
    assert (problem.code, problem.severity, problem.field) == (
        "shared-input",
        "info",
        "input_int_register_24",
    )
    assert "a, b" in problem.message


def test_every_problem_reported_at_once_for_a_file() -> None:
    from rtde_spec.recipes.files import load_recipes

    report = validate_recipes(load_recipes(DATA / "ur_client_config.xml"), controller="3.8.0")
    found = codes(report)
    # registers 24+ arrived in 3.9.0: both input recipes fail on 3.8.0
    assert found["not-available"] == [
        "input_double_register_24",
        "input_double_register_25",
        "input_int_register_24",
    ]
    assert [r.direction for r in report.recipes] == ["output", "input", "input"]


def test_controller_answer_is_what_the_emulator_sends() -> None:
    answer = controller_answer(["timestamp", "nope", "target_gravity"], "output", "5.25.0")
    assert answer == ["DOUBLE", NOT_FOUND, NOT_FOUND]
    assert controller_answer(["target_gravity"], "output", "5.26.0") == ["VECTOR3D"]


def test_third_party_fields_warn() -> None:
    report = check("timestamp,control_step", controller="5.12.2")
    assert report.valid and codes(report) == {"undocumented": ["control_step"]}  # type: ignore[attr-defined]


def test_each_recipe_is_checked_against_its_own_controller() -> None:
    old = Recipe(("timestamp", "safety_status"), direction="output", controller="3.9.0", key="old")
    new = Recipe(("timestamp", "safety_status"), direction="output", controller="5.4.0", key="new")
    report = validate_recipes([old, new])
    assert [r.valid for r in report.recipes] == [False, True]
    assert report.controller is None
    forced = validate_recipes([old, new], controller="5.12.2")
    assert forced.valid and forced.controller == "5.12.2" and forced.line == "e-series"


def test_recipes_without_a_version_among_others_are_flagged() -> None:
    named = Recipe(("timestamp",), direction="output", controller="5.12.2", key="a")
    unnamed = Recipe(("timestamp",), direction="output", key="b")
    report = validate_recipes([named, unnamed])
    assert "no-controller" in codes(report)


def test_what_user_code_passes_instead_of_recipes_is_named() -> None:
    """Names instead of recipes, a bad direction or version string raised AttributeError,
    KeyError or a bare ValueError from inside; one string as a recipe's names was read a
    character a name ("t: unknown field", "i: unknown field", ...)."""
    for given in (["timestamp", "actual_q"], "timestamp", Recipe(("timestamp",))):
        with pytest.raises(UsageError, match="takes a list of Recipe"):
            validate_recipes(given)  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="direction must be input or output, not 'out'"):
        validate_recipes([Recipe(("timestamp",))], direction="out")  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="not 'outputs'"):
        validate_recipes([Recipe(("timestamp",), direction="outputs")])  # type: ignore[arg-type]
    for version in ("bogus", "v5.4", 5):
        with pytest.raises(RecipeError, match="bad version string") as info:
            validate_recipes([Recipe(("timestamp",))], controller=version)  # type: ignore[arg-type]
        assert info.value.subject == "controller version"
    assert Recipe("timestamp,actual_q").names == ("timestamp", "actual_q")  # type: ignore[arg-type]
    assert Recipe(["timestamp"]).names == ("timestamp",)  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="None is a NoneType"):
        Recipe(("timestamp", None))  # type: ignore[arg-type]
