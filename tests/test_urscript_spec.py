"""spec/urscript/functions.yaml is what the emulator's URScript implements, no more and no less,
and its meta-model refuses a malformed table with the file and the entry."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.emulator.urscript import builtins
from rtde_spec.errors import SpecError
from rtde_spec.metamodel.urscript import load_urscript, urscript_functions

ROOT = Path(__file__).resolve().parent.parent


def test_the_interpreter_implements_every_function_the_spec_lists_and_no_other() -> None:
    listed = {f.name for f in urscript_functions().functions}
    implemented = builtins.names()
    assert sorted(listed - implemented) == []  # claimed but not run
    assert sorted(implemented - listed) == []  # run but not in the spec


def test_the_generated_table_is_the_yaml() -> None:
    assert load_urscript(ROOT / "spec") == urscript_functions()


def test_the_drivers_programs_call_only_listed_functions() -> None:
    """The built-ins ur_rtde's control script and URCL's external control call (as read from their
    programs by hand, names only) are all in the table."""
    listed = {f.name for f in urscript_functions().functions}
    ur_rtde = (
        "read_input_integer_register read_input_float_register write_output_integer_register "
        "write_output_float_register get_steptime servoc servoj speedj speedl movej movel stopj stopl "
        "force_mode end_force_mode force_mode_set_damping force_mode_set_gain_scaling zero_ftsensor "
        "freedrive_mode end_freedrive_mode get_freedrive_status teach_mode end_teach_mode set_tcp "
        "set_payload get_inverse_kin get_forward_kin get_inverse_kin_has_solution pose_sub pose_trans "
        "is_steady textmsg rtde_set_watchdog tool_contact protective_stop get_actual_tcp_pose norm sync"
    ).split()
    urcl = (
        "socket_open socket_close socket_read_binary_integer socket_send_int movec str_cat popup "
        "get_joint_positions get_target_joint_positions get_steptime sleep"
    ).split()
    assert sorted(set(ur_rtde + urcl) - listed) == []


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            "  - {name: movej, section: motion, returns: none, since: {cb3: 3.0.0}, doc: again}\n",
            "given twice",
        ),
        (
            "  - {name: f, section: motion, returns: none, since: {cb3: 3.0.0}, doc: x,\n"
            "     params: [{name: a, default: 1}, {name: b}]}\n",
            "required parameter 'b' after an optional one",
        ),
        (
            "  - {name: g, section: motion, returns: none, since: {cb4: 3.0.0}, doc: x}\n",
            "not a product line",
        ),
        ("  - {name: h, section: motion, returns: maybe, since: {cb3: 3.0.0}, doc: x}\n", "returns"),
    ],
)
def test_a_malformed_table_names_the_file_and_the_problem(tmp_path: Path, change: str, message: str) -> None:
    text = (ROOT / "spec" / "urscript" / "functions.yaml").read_text(encoding="utf-8") + change
    (tmp_path / "urscript").mkdir()
    (tmp_path / "urscript" / "functions.yaml").write_text(text, encoding="utf-8")
    with pytest.raises(SpecError, match=re.escape("urscript/functions.yaml")) as caught:
        load_urscript(tmp_path)
    assert message in str(caught.value)


@pytest.mark.parametrize(
    ("version", "refused"),
    [("5.4.0", True), ("5.10.0", False), ("3.15.0", True)],  # get_target_payload: e-Series 5.10 on
)
def test_a_function_the_controller_version_lacks_is_a_compile_error(version: str, refused: bool) -> None:
    from rtde_spec.emulator.controller.model import ControllerModel

    model = ControllerModel(version)
    model.run_script("m = get_target_payload()")
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert (("runtime_exception", "compile_error_name_not_found:get_target_payload:") in events) is refused
