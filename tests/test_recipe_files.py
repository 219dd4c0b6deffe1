"""Recipe files in every format: load, save, round trip, and hostile input."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.errors import RecipeError
from rtde_spec.recipes.files import FORMATS, dumps_recipes, load_recipes, save_recipes
from rtde_spec.recipes.model import Recipe
from tests.budget import examples

from .helpers import DATA


def test_ur_client_xml() -> None:
    recipes = load_recipes(DATA / "ur_client_config.xml")
    assert [r.key for r in recipes] == ["state", "setp", "watchdog"]
    assert recipes[0].names == ("timestamp", "actual_q", "robot_mode", "output_int_register_0")
    assert recipes[0].declared_types["actual_q"] == "VECTOR6D"
    assert recipes[1].names == ("input_double_register_24", "input_double_register_25")


def test_comma_list_keeps_order_and_drops_a_trailing_comma() -> None:
    assert Recipe.parse("timestamp, actual_q,").names == ("timestamp", "actual_q")
    assert Recipe.parse("a,,b").names == ("a", "", "b")


@pytest.mark.parametrize(
    "fmt,suffix", [("xml", ".xml"), ("yaml", ".yaml"), ("json", ".json"), ("lines", ".txt"), ("csv", ".csv")]
)
def test_round_trip(tmp_path: Path, fmt: str, suffix: str) -> None:
    recipe = Recipe(("timestamp", "actual_q", "robot_mode"), key="state")
    if fmt in ("yaml", "json"):
        recipe = recipe.with_(direction="output", frequency=125.0, controller="5.12.2")
    if fmt == "xml":
        recipe = recipe.with_(
            declared_types={"timestamp": "DOUBLE", "actual_q": "VECTOR6D", "robot_mode": "INT32"}
        )
    path = tmp_path / f"recipe{suffix}"
    save_recipes([recipe], path)
    (back,) = load_recipes(path)
    assert back.names == recipe.names
    if fmt in ("yaml", "json", "xml"):
        assert back.key == "state"
        assert back.declared_types == recipe.declared_types
    if fmt in ("yaml", "json"):
        assert (back.direction, back.frequency, back.controller) == ("output", 125.0, "5.12.2")
    assert dumps_recipes([back.with_(source=None)], fmt) == dumps_recipes([recipe], fmt)


def test_xml_round_trip_of_several_recipes(tmp_path: Path) -> None:
    original = load_recipes(DATA / "ur_client_config.xml")
    path = tmp_path / "again.xml"
    save_recipes(original, path)
    again = load_recipes(path)
    assert [(r.key, r.names, r.declared_types) for r in again] == [
        (r.key, r.names, r.declared_types) for r in original
    ]


def test_xml_types_filled_from_the_spec_on_save() -> None:
    text = dumps_recipes([Recipe(("timestamp",))], "xml", types={"timestamp": "DOUBLE"})
    assert '<field name="timestamp" type="DOUBLE" />' in text


def test_single_recipe_formats_refuse_several() -> None:
    with pytest.raises(RecipeError, match="holds one recipe"):
        dumps_recipes([Recipe(("a",)), Recipe(("b",))], "lines")


def test_lines_format_skips_comments_and_blanks(tmp_path: Path) -> None:
    path = tmp_path / "outputs.txt"
    path.write_text("# the C++ client's format\ntimestamp\n\nactual_q  # joints\n")
    assert load_recipes(path)[0].names == ("timestamp", "actual_q")


def test_yaml_list_shapes(tmp_path: Path) -> None:
    path = tmp_path / "r.yaml"
    path.write_text("- timestamp\n- actual_q\n")
    assert load_recipes(path)[0].names == ("timestamp", "actual_q")
    path.write_text("recipes:\n  - fields: [timestamp]\n    colour: red\n")
    with pytest.raises(RecipeError, match="unknown key"):
        load_recipes(path)


BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;">]>
<rtde_config><recipe key="x"><field name="&lol2;" type="DOUBLE"/></recipe></rtde_config>
"""
EXTERNAL = """<?xml version="1.0"?>
<!DOCTYPE r [<!ENTITY xxe SYSTEM "file:///etc/passwd">]>
<rtde_config><recipe key="x"><field name="&xxe;"/></recipe></rtde_config>
"""


@pytest.mark.parametrize("text", [BILLION_LAUGHS, EXTERNAL], ids=["entity-expansion", "external"])
def test_hostile_xml_is_refused(tmp_path: Path, text: str) -> None:
    path = tmp_path / "evil.xml"
    path.write_text(text)
    with pytest.raises(RecipeError, match="unsafe XML refused"):
        load_recipes(path)


def test_oversized_file_is_refused_before_parsing(tmp_path: Path) -> None:
    path = tmp_path / "huge.xml"
    path.write_text("<rtde_config>" + " " * (1 << 20) + "</rtde_config>")
    with pytest.raises(RecipeError, match="too large"):
        load_recipes(path)


def test_malformed_xml_names_the_position(tmp_path: Path) -> None:
    path = tmp_path / "bad.xml"
    path.write_text('<rtde_config>\n<recipe key="a">\n<field name="x">\n</rtde_config>\n')
    with pytest.raises(RecipeError, match="line 4"):
        load_recipes(path)


def test_wrong_root_and_missing_name(tmp_path: Path) -> None:
    path = tmp_path / "r.xml"
    path.write_text("<config/>")
    with pytest.raises(RecipeError, match="rtde_config"):
        load_recipes(path)
    path.write_text('<rtde_config><recipe key="a"><field type="DOUBLE"/></recipe></rtde_config>')
    with pytest.raises(RecipeError, match="without a name"):
        load_recipes(path)


# URBasic's rtdeConfigurationDefault.xml as it ships (Rope Robotics' URBasic/rtde.py reads it:
# <receive> holds what it asks the controller for, <send> what it writes, each field with an
# initValue it sends first); a commented-out line and a stray "-->" left in the text as it has them
URBASIC_XML = """<?xml version="1.0"?>
<!-- Universal Robots do not support more than 96 values in recieve or send config at one time  -->
<rtde_config>
    <receive key="out">
        <!--<field name="target_q" type="VECTOR6D"/>-->
        <field name="actual_q" type="VECTOR6D"/>
        <field name="speed_scaling" type="DOUBLE"/>-->
        <field name="output_int_register_0" type="INT32"/>
    </receive>
    <send key="in">
        <field name="input_int_register_0" type="INT32" initValue="0"/>
        <field name="standard_digital_output_mask" type="UINT8" initValue="0"/>
    </send>
</rtde_config>
"""


def test_urbasic_receive_and_send_elements_are_its_output_and_input_recipes(tmp_path: Path) -> None:
    path = tmp_path / "rtdeConfigurationDefault.xml"
    path.write_text(URBASIC_XML)
    out, into = load_recipes(path)
    assert (out.key, out.direction, out.names) == (
        "out", "output", ("actual_q", "speed_scaling", "output_int_register_0"),
    )  # fmt: skip
    assert out.declared_types["actual_q"] == "VECTOR6D"
    assert (into.key, into.direction, into.names) == (
        "in", "input", ("input_int_register_0", "standard_digital_output_mask"),
    )  # fmt: skip


def test_validate_reads_urbasic_s_file_with_each_direction(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from rtde_spec.cli.main import main

    path = tmp_path / "rtdeConfigurationDefault.xml"
    path.write_text(URBASIC_XML.replace('"input_int_register_0"', '"actual_q"'))  # an output under <send>
    assert main(["validate", str(path), "--controller", "5.15.0"]) == 1
    report = capsys.readouterr().out
    assert "out (output, 3 fields" in report and "in (input, 2 fields" in report
    assert "actual_q" in report.split("in (input")[1]  # the output named under <send> is the fault


def test_an_rtde_config_without_recipes_names_what_it_holds(tmp_path: Path) -> None:
    path = tmp_path / "r.xml"
    path.write_text('<rtde_config><recipes><field name="actual_q"/></recipes></rtde_config>')
    with pytest.raises(RecipeError, match=r"no <recipe> elements.*<recipes>"):
        load_recipes(path)


def test_formats_are_all_covered() -> None:
    assert set(FORMATS) == {"xml", "lines", "csv", "yaml", "json"}


@pytest.mark.parametrize("fmt", FORMATS)
def test_random_text_gives_recipes_or_recipe_error(tmp_path: Path, fmt: str) -> None:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from rtde_spec.recipes.validation import validate_recipes

    @settings(
        max_examples=examples(80), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
    )
    @given(st.text(max_size=200))
    def check(text: str) -> None:
        path = tmp_path / "r.any"
        path.write_text(text, encoding="utf-8")
        try:
            recipes = load_recipes(path, fmt)
        except RecipeError as exc:
            assert str(exc)
            return
        report = validate_recipes(recipes)  # whatever loads can be validated without crashing
        assert isinstance(report.valid, bool)

    check()


UR_XML = """<?xml version="1.0"{decl}?>
<!-- {comment} -->
<rtde_config>
  <recipe key="state">
    <field name="timestamp" type="DOUBLE"/>
    <field name="actual_q
" type="VECTOR6D"/>
  </recipe>
</rtde_config>
"""


@pytest.mark.parametrize(
    ("name", "data"),
    [
        ("bom.txt", "\ufefftimestamp\r\nactual_q\r\n".encode()),
        ("bom.csv", "\ufefftimestamp,actual_q\r\n".encode()),
        ("bom.json", '\ufeff["timestamp", "actual_q"]'.encode()),
        ("bom.yaml", "\ufefffields: [timestamp, actual_q]\n".encode()),
        ("quoted.csv", b'"timestamp","actual_q"\r\n'),
        ("semicolons.csv", b"timestamp;actual_q;\n"),
        ("semicolons.txt", b"timestamp; actual_q\n"),
        ("bom.xml", ("\ufeff" + UR_XML.format(decl="", comment="Notepad")).encode()),
        ("bom-xml.txt", ("\ufeff" + UR_XML.format(decl="", comment="saved as .txt")).encode()),
        ("utf16.xml", UR_XML.format(decl=' encoding="UTF-16"', comment="Größe").encode("utf-16")),
        ("cp1252.xml", UR_XML.format(decl=' encoding="windows-1252"', comment="Größe €").encode("cp1252")),
        ("latin1.xml", UR_XML.format(decl=" encoding='ISO-8859-1'", comment="Größe").encode("latin-1")),
        ("dotnet.xml", UR_XML.format(decl=' encoding="utf-16"', comment="Größe").encode()),  # UTF-8 after all
    ],
)
def test_files_as_editors_save_them(tmp_path: Path, name: str, data: bytes) -> None:
    """A byte-order mark (Notepad, PowerShell, Excel), UTF-16, an XML declaration's encoding,
    quoted or semicolon-separated CSV, a line break inside an XML name: the same two names.
    Before, the mark became part of the first name and the declared encoding was ignored."""
    path = tmp_path / name
    path.write_bytes(data)
    (recipe,) = load_recipes(path)
    assert recipe.names == ("timestamp", "actual_q")


def test_text_in_no_encoding_it_claims_is_named(tmp_path: Path) -> None:
    path = tmp_path / "r.xml"
    path.write_bytes(UR_XML.format(decl=' encoding="no-such-codec"', comment="x").encode())
    with pytest.raises(RecipeError, match="unknown encoding 'no-such-codec'"):
        load_recipes(path)
    path.write_bytes(b"timestamp\n\xff\xfeactual_q\n")
    with pytest.raises(RecipeError, match="not utf-8 text at byte 10: save it as UTF-8"):
        load_recipes(path)


@pytest.mark.parametrize("suffix", [".json", ".yaml"])
def test_numeric_keys_are_chosen_by_their_text(tmp_path: Path, suffix: str) -> None:
    """`key: 1` in YAML or JSON is the number 1; `--recipe-key 1` took the first recipe instead."""
    from rtde_spec.recipes.files import pick_recipe

    path = tmp_path / f"keys{suffix}"
    path.write_text('{"recipes": [{"key": 2, "fields": ["timestamp"]}, {"key": 1, "fields": ["actual_qd"]}]}')
    recipes = load_recipes(path)
    assert [r.key for r in recipes] == ["2", "1"]
    chosen = pick_recipe(recipes, "1", "output", set(), {"timestamp", "actual_qd"}, where=str(path))
    assert chosen.names == ("actual_qd",)


@pytest.mark.parametrize(
    "text", ["controller: 5.10\nfields: [timestamp]\n", '{"controller": 5.10, "fields": ["timestamp"]}']
)
def test_a_controller_version_read_as_a_number_is_refused(tmp_path: Path, text: str) -> None:
    """YAML and JSON read 5.10 as 5.1: validated for the wrong controller, before."""
    path = tmp_path / ("r.yaml" if text.startswith("c") else "r.json")
    path.write_text(text)
    with pytest.raises(RecipeError, match=r"controller must be a version in quotes \('5.10'"):
        load_recipes(path)
    path.write_text(text.replace("5.10", '"5.10"'))
    assert load_recipes(path)[0].controller == "5.10"


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("fields: [{timestamp: DOUBLE}, actual_q]\n", "recipe 1: {'timestamp': 'DOUBLE'} is no name"),
        ("fields: [timestamp, null]\n", "recipe 1: None is no name"),
        ("- [timestamp]\n- [timestamp, 5]\n", "recipe 2: 5 is no name"),
        ("fields: [timestamp]\nfrequency: true\n", "recipe 1: frequency must be a number (got True)"),
    ],
)
def test_an_entry_that_is_no_name_is_named_with_its_recipe(tmp_path: Path, text: str, said: str) -> None:
    """A mapping without `name`, null and numbers became the names "None" and "5" (validated as
    unknown fields, the cause unsaid); `frequency: true` was 1 Hz; recipes were counted from 0."""
    path = tmp_path / "r.yaml"
    path.write_text(text)
    with pytest.raises(RecipeError, match=re.escape(said)):
        load_recipes(path)


@pytest.mark.parametrize("fmt", ["yaml", "json", "xml"])
def test_what_a_recipe_file_cannot_read_back_is_not_written(tmp_path: Path, fmt: str) -> None:
    """No recipe wrote a file load_recipes refuses; a NaN rate wrote JSON's NaN."""
    from rtde_spec.errors import RecipeError
    from rtde_spec.recipes.files import save_recipes
    from rtde_spec.recipes.model import Recipe

    out = tmp_path / f"r.{fmt}"
    with pytest.raises(RecipeError, match="no recipes to write"):
        save_recipes([], out)
    with pytest.raises(RecipeError, match="frequency must be a finite number"):
        save_recipes([Recipe(("timestamp",), frequency=float("nan"))], out)
    assert not out.exists()
