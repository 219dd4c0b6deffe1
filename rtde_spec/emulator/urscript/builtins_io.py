"""The I/O built-ins PolyScope's program preamble calls from the installation, and the reads of the
I/O: input domains, the tool connector's modes and serial interface, how outputs follow the
program (runstate), Modbus signals, and get_*_digital/analog_in/out.

What a client can see is set where it sees it: the analog input domains in RTDE's analog_io_types
and tool_analog_input_types (the primary Masterboard and Tool Data read the same values), the tool
output modes in tool_output_mode and tool_digital_output<n>_mode (and the primary Tool Mode Info),
the serial interface on the robot's `tool_communication` (the primary Tool Communication Info), and
the runstate choices on the robot's `set_runstate`, since they outlive the program (the controller
applies them when a program starts and ends). What nothing shows (input actions, Modbus signals,
the emulator has no Modbus client) is recorded with the program (`settings_of`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rtde_spec._generated.enums import AnalogIoTypes, DigitalIoBits, ToolAnalogInputTypes
from rtde_spec.emulator.urscript.builtins_modes import settings_of
from rtde_spec.emulator.urscript.calls import arg, number, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
IO: dict[str, Builtin] = {}

DOMAINS = {0: "current (4-20 mA)", 1: "voltage (0-10 V)"}  # the Script manual's analog input domains
BAUD_RATES = (9600, 19200, 38400, 57600, 115200, 1_000_000, 2_000_000, 5_000_000)
TOOL_DIGITAL_OUTPUT_MODES = {1: "sinking (NPN)", 2: "sourcing (PNP)", 3: "push-pull"}
# the runstate choices (set_runstate_*_output_to_value); the tool outputs have no drive-power ones
RUNSTATES = {"standard": range(8), "configurable": range(8), "tool": range(6)}
MAX_SIGNAL_NAME = 20  # characters of a Modbus signal's name
# where each group of digital I/O starts in actual_digital_input_bits / actual_digital_output_bits
_SHIFT = {
    "standard": DigitalIoBits.STANDARD_0.bit_length() - 1,
    "configurable": DigitalIoBits.CONFIGURABLE_0.bit_length() - 1,
    "tool": DigitalIoBits.TOOL_0.bit_length() - 1,
}
_PINS = {"standard": 8, "configurable": 8, "tool": 2}


_builtin = registrar(IO)


def _int(stmt: Stmt, value: Any, name: str, allowed: Any) -> int:
    """An int argument within `allowed` (a range, tuple or dict of the manual's values)."""
    if not isinstance(value, int) or isinstance(value, bool) or value not in allowed:
        shown = ", ".join(str(v) for v in allowed)
        raise ScriptFault(f"{stmt.name}: {name} must be one of {shown}, not {value!r}", stmt.line, 1)
    return value


def _bit(values: dict[str, Any], key: str, bit: int, on: bool) -> None:
    current = int(values.get(key, 0))
    values[key] = (current | bit) if on else (current & ~bit)


# --- the installation's I/O setup ---------------------------------------------------------------


@_builtin("set_standard_analog_input_domain", "set_tool_analog_input_domain")
def _input_domain(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Domain 1 (voltage) sets the input's bit, 0 (current) clears it, as RTDE encodes it."""
    port = _int(stmt, arg(stmt, args, kwargs, 0, "port"), "port", (0, 1))
    domain = _int(stmt, arg(stmt, args, kwargs, 1, "domain"), "domain", DOMAINS)
    _domain(runner, stmt, stmt.name == "set_standard_analog_input_domain", port, domain == 1)


def _domain(runner: Runner, stmt: Stmt, standard: bool, port: int, voltage: bool) -> None:
    if standard:
        bits = (AnalogIoTypes.ANALOG_INPUT_0_VOLTAGE, AnalogIoTypes.ANALOG_INPUT_1_VOLTAGE)
        _bit(runner.robot.values, "analog_io_types", int(bits[port]), voltage)
    else:
        tool = tuple(ToolAnalogInputTypes)  # input 0's bit, input 1's
        _bit(runner.robot.values, "tool_analog_input_types", int(tool[port]), voltage)
    runner.applied.append(stmt.text)


@_builtin("set_analog_inputrange")
def _input_range(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """The deprecated form (CB2/CB3 preambles, python-urx's Robotiq program): ports 0-1 the
    controller's, range 0 (0-5 V, taken as 2) or 2 (0-10 V); 2-3 the tool's, range 0 (0-5 V,
    taken as 1) or 1 (0-10 V) voltage, 2 current (4-20 mA). The controller's ranges 1 and 3 (-5-5 V,
    -10-10 V) are "no longer supported" (the Script Directory), so refused."""
    port = _int(stmt, arg(stmt, args, kwargs, 0, "port"), "port", range(4))
    allowed = (0, 2) if port < 2 else (0, 1, 2)
    chosen = _int(stmt, arg(stmt, args, kwargs, 1, "range"), "range", allowed)
    _domain(runner, stmt, port < 2, port % 2, port < 2 or chosen != 2)


@_builtin("set_input_actions_to_default")
def _input_actions(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    settings_of(runner)["_input_actions"] = "default"  # no input action is modelled


@_builtin("set_tool_output_mode")
def _tool_output_mode(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    mode = _int(stmt, arg(stmt, args, kwargs, 0, "mode"), "mode", (0, 1))
    runner.robot.values["tool_output_mode"] = mode
    runner.applied.append(stmt.text)


@_builtin("set_tool_digital_output_mode")
def _tool_digital_output_mode(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    n = _int(stmt, arg(stmt, args, kwargs, 0, "n"), "n", (0, 1))
    mode = _int(stmt, arg(stmt, args, kwargs, 1, "mode"), "mode", TOOL_DIGITAL_OUTPUT_MODES)
    runner.robot.values[f"tool_digital_output{n}_mode"] = mode
    runner.applied.append(stmt.text)


@_builtin("set_tool_communication")
def _tool_communication(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """The Tool Communication Interface's settings, checked against the manual's ranges."""
    enabled = arg(stmt, args, kwargs, 0, "enabled")
    if not isinstance(enabled, bool):
        raise ScriptFault(f"{stmt.name}: enabled must be a bool, not {type_name(enabled)}", stmt.line, 1)
    baud = _int(stmt, arg(stmt, args, kwargs, 1, "baud_rate"), "baud_rate", BAUD_RATES)
    parity = _int(stmt, arg(stmt, args, kwargs, 2, "parity"), "parity", (0, 1, 2))
    stop_bits = _int(stmt, arg(stmt, args, kwargs, 3, "stop_bits"), "stop_bits", (1, 2))
    rx_idle = number(stmt, arg(stmt, args, kwargs, 4, "rx_idle_chars"), "rx_idle_chars")
    tx_idle = number(stmt, arg(stmt, args, kwargs, 5, "tx_idle_chars"), "tx_idle_chars")
    if not (1.0 <= rx_idle <= 40.0 and 0.0 <= tx_idle <= 40.0):
        raise ScriptFault(
            f"{stmt.name}: rx_idle_chars must be 1 to 40 and tx_idle_chars 0 to 40, "
            f"not {rx_idle:g} and {tx_idle:g}",
            stmt.line,
            1,
        )
    settings = {
        "tool_communication_is_enabled": enabled,
        "baud_rate": baud,
        "parity": parity,
        "stop_bits": stop_bits,
        "rx_idle_chars": rx_idle,
        "tx_idle_chars": tx_idle,
    }
    shown = getattr(runner.robot, "tool_communication", None)
    if isinstance(shown, dict):  # the controller's: it outlives the program
        shown.update(settings)
    settings_of(runner)["_tool_communication"] = settings
    runner.applied.append(stmt.text)


@_builtin(
    "set_runstate_standard_digital_output_to_value",
    "set_runstate_configurable_digital_output_to_value",
    "set_runstate_tool_digital_output_to_value",
)
def _runstate(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    group = stmt.name.split("_")[2]
    output = _int(stmt, arg(stmt, args, kwargs, 0, "outputId"), "outputId", range(_PINS[group]))
    state = _int(stmt, arg(stmt, args, kwargs, 1, "state"), "state", RUNSTATES[group])
    apply = getattr(runner.robot, "set_runstate", None)
    if apply is not None:
        apply(group, output, state)
    runner.applied.append(stmt.text)


@_builtin("set_runstate_standard_digital_outputs", "set_runstate_outputs")
def _runstate_outputs(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Which outputs follow the program's run state; set_runstate_outputs is the CB2-era name
    (CB3 preambles and python-urx's Robotiq program call it with [] for none)."""
    default: Any = [] if stmt.name == "set_runstate_outputs" else ...
    outputs = arg(stmt, args, kwargs, 0, "outputs", default)
    if not isinstance(outputs, list) or not all(type(o) is int for o in outputs):
        raise ScriptFault(f"{stmt.name}: outputs must be a list of output numbers", stmt.line, 1)
    settings_of(runner)["_runstate_standard_digital_outputs"] = list(outputs)  # undocumented: recorded


# --- Modbus signals: recorded, never polled (the emulator has no Modbus client); an output keeps
#     what the program set, an input reads False or 0 --------------------------------------------


def _signals(runner: Runner) -> dict[str, dict[str, Any]]:
    signals: dict[str, dict[str, Any]] = settings_of(runner).setdefault("modbus_signals", {})
    return signals


def _signal_name(stmt: Stmt, value: Any) -> str:
    if not isinstance(value, str) or not 0 < len(value) <= MAX_SIGNAL_NAME:
        what = f"signal_name must be a text of 1 to {MAX_SIGNAL_NAME} characters"
        raise ScriptFault(f"{stmt.name}: {what}", stmt.line, 1)
    return value


@_builtin("modbus_add_signal")
def _modbus_add(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    address = arg(stmt, args, kwargs, 0, "IP")
    if not isinstance(address, str) or not address:
        raise ScriptFault(f"{stmt.name}: IP must be a text that is not empty", stmt.line, 1)
    slave = _int(stmt, arg(stmt, args, kwargs, 1, "slave_number"), "slave_number", range(256))
    register = arg(stmt, args, kwargs, 2, "signal_address")
    if not isinstance(register, int) or isinstance(register, bool) or register < 0:
        raise ScriptFault(f"{stmt.name}: signal_address must be an int of 0 or more", stmt.line, 1)
    kind = _int(stmt, arg(stmt, args, kwargs, 3, "signal_type"), "signal_type", (0, 1, 2, 3, 15, 16))
    name = _signal_name(stmt, arg(stmt, args, kwargs, 4, "signal_name"))
    sequential = bool(arg(stmt, args, kwargs, 5, "sequential_mode", False))
    count = _int(stmt, arg(stmt, args, kwargs, 6, "register_count", 1), "register_count", range(1, 124))
    _signals(runner)[name] = {
        "ip": address, "slave": slave, "address": register, "type": kind, "sequential": sequential,
        "count": count, "update_frequency": 10, "runstate_choice": 0,
    }  # fmt: skip


@_builtin("modbus_add_rw_signal")
def _modbus_add_rw(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """A signal of registers read from one address and written to another with function code 23
    (read_register_count and write_register_count 1 to 123)."""
    address = arg(stmt, args, kwargs, 0, "IP")
    if not isinstance(address, str) or not address:
        raise ScriptFault(f"{stmt.name}: IP must be a text that is not empty", stmt.line, 1)
    slave = _int(stmt, arg(stmt, args, kwargs, 1, "slave_number"), "slave_number", range(256))
    fields = ("read_address", "read_register_count", "write_address", "write_register_count")
    read_at, reads, write_at, writes = (arg(stmt, args, kwargs, 2 + i, f) for i, f in enumerate(fields))
    for field, value in zip(fields, (read_at, reads, write_at, writes), strict=True):
        low, top = (1, 123) if field.endswith("count") else (0, 0xFFFF)
        if type(value) is not int or not low <= value <= top:
            raise ScriptFault(
                f"{stmt.name}: {field} must be an int of {low} to {top}, not {value!r}", stmt.line, 1
            )
    name = _signal_name(stmt, arg(stmt, args, kwargs, 6, "signal_name"))
    sequential = bool(arg(stmt, args, kwargs, 7, "sequential_mode", False))
    _signals(runner)[name] = {
        "ip": address, "slave": slave, "address": write_at, "read_address": read_at, "type": _RW,
        "sequential": sequential, "count": writes, "read_count": reads, "update_frequency": 10,
        "runstate_choice": 0,
    }  # fmt: skip


@_builtin("modbus_set_signal_watchdog")
def _modbus_watchdog(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """How long (0 to 300 s; 2 s by default) errors are tolerated before the program stops."""
    signal = _signal(runner, stmt, _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name")))
    timeout = number(stmt, arg(stmt, args, kwargs, 1, "new_timeout_in_sec"), "new_timeout_in_sec")
    if not 0 <= timeout <= 300:
        raise ScriptFault(f"{stmt.name}: new_timeout_in_sec must be 0 to 300, not {timeout:g}", stmt.line, 1)
    signal["watchdog"] = timeout


@_builtin("modbus_get_error", "modbus_get_time_since_signal_invalid")
def _modbus_error(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int | float:
    """No device is polled, so none fails: no error (0) and no time in error (0.0)."""
    _signal(runner, stmt, _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name")))
    if stmt.name == "modbus_get_time_since_signal_invalid":
        return 0.0
    _int(stmt, arg(stmt, args, kwargs, 1, "error_source", 0), "error_source", (0, 1, 2))
    return 0


@_builtin("modbus_set_signal_update_frequency", "modbus_set_runstate_dependent_choice")
def _modbus_setting(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    name = _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name"))
    if stmt.name == "modbus_set_signal_update_frequency":
        key, allowed = "update_frequency", range(-1, 501)
    else:
        key, allowed = "runstate_choice", range(6)
    value = _int(stmt, arg(stmt, args, kwargs, 1, key), key, allowed)
    _signal(runner, stmt, name)[key] = value


def _signal(runner: Runner, stmt: Stmt, name: str) -> dict[str, Any]:
    signal = _signals(runner).get(name)
    if signal is None:
        raise ScriptFault(f"{stmt.name}: no Modbus signal {name!r} (modbus_add_signal adds it)", stmt.line, 1)
    return signal


@_builtin("modbus_delete_signal")
def _modbus_delete(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    name = _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name"))
    _signal(runner, stmt, name)
    del _signals(runner)[name]


_DIGITAL = (0, 1, 15)  # signal types: digital input, output, outputs (register_count coils)
_RW = 23  # modbus_add_rw_signal's: registers read from one address and written to another
_MANY = (15, 16, _RW)  # outputs of several coils / registers


def _many(signal: dict[str, Any]) -> bool:
    """A signal of several coils or registers: its value is a list (UR's wago-750 example reads 24
    digital inputs as one signal of register_count 24)."""
    return signal["type"] in _MANY or signal["count"] > 1


def _current(signal: dict[str, Any]) -> Any:
    """What a signal holds: what the program set, else False or 0 (no device answers)."""
    zero: Any = False if signal["type"] in _DIGITAL else 0
    return signal.get("value", [zero] * signal["count"] if _many(signal) else zero)


@_builtin("modbus_get_signal_status")
def _modbus_get(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    """A digital signal's bool, a register's unsigned int, a list of them for a signal of several."""
    signal = _signal(runner, stmt, _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name")))
    arg(stmt, args, kwargs, 1, "is_secondary_program", False)
    if signal["type"] == _RW:  # what the device's read registers hold: none answers
        return [0] * signal["read_count"] if signal["read_count"] > 1 else 0
    value = _current(signal)
    return list(value) if isinstance(value, list) else value


@_builtin("modbus_set_output_signal", "modbus_set_output_register")
def _modbus_set(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """An output's value, or a list of values from its first (a shorter list keeps the rest)."""
    name = _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name"))
    signal = _signal(runner, stmt, name)
    digital = stmt.name == "modbus_set_output_signal"
    value = arg(stmt, args, kwargs, 1, "digital_value" if digital else "register_value")
    arg(stmt, args, kwargs, 2, "is_secondary_program", False)
    kinds, what = ((1, 15), "digital output") if digital else ((3, 16, _RW), "register output")
    if signal["type"] not in kinds:
        raise ScriptFault(f"{stmt.name}: {name!r} is no {what}", stmt.line, 1)
    many = _many(signal)
    values = value if many and isinstance(value, list) else [value]
    if not 0 < len(values) <= signal["count"] or not all(_fits(v, digital) for v in values):
        shape = "a bool" if digital else "an int of 0 to 65535"
        shape += f" (or a list of 1 to {signal['count']})" if many else ""
        raise ScriptFault(f"{stmt.name}: the value must be {shape}, not {value!r}"[:200], stmt.line, 1)
    signal["value"] = values + _current(signal)[len(values) :] if many else value


def _fits(value: Any, digital: bool) -> bool:
    return isinstance(value, bool) if digital else type(value) is int and 0 <= value <= 0xFFFF


@_builtin("modbus_send_custom_command")
def _modbus_custom(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Checked and dropped: no Modbus device is there to send it to."""
    address = arg(stmt, args, kwargs, 0, "IP")
    if not isinstance(address, str) or not address:
        raise ScriptFault(f"{stmt.name}: IP must be a text that is not empty", stmt.line, 1)
    _int(stmt, arg(stmt, args, kwargs, 1, "slave_number"), "slave_number", range(256))
    function = arg(stmt, args, kwargs, 2, "function_code")
    data = arg(stmt, args, kwargs, 3, "data")
    if (
        type(function) is not int
        or not isinstance(data, list)
        or not all(_fits(d, False) and d < 256 for d in data)
    ):
        raise ScriptFault(f"{stmt.name}: function_code must be an int and data a list of bytes", stmt.line, 1)


# --- reading the I/O ----------------------------------------------------------------------------


def _digital(group: str, key: str) -> Builtin:
    def read(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
        n = _int(stmt, arg(stmt, args, kwargs, 0, "n"), "n", range(_PINS[group]))
        return bool(int(runner.robot.values.get(key, 0)) >> (_SHIFT[group] + n) & 1)

    return read


def _deprecated_digital(key: str) -> Builtin:
    def read(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
        n = _int(stmt, arg(stmt, args, kwargs, 0, "n"), "n", range(10))  # 8 and 9: the tool's
        bit = _SHIFT["standard"] + n if n < 8 else _SHIFT["tool"] + n - 8
        return bool(int(runner.robot.values.get(key, 0)) >> bit & 1)

    return read


def _analog(prefixes: tuple[str, ...]) -> Builtin:
    """get_*_analog_in/out(n): `prefixes` are the outputs' names per pair of ports (the deprecated
    get_analog_in numbers the standard inputs 0-1 and the tool's 2-3)."""

    def read(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
        n = _int(stmt, arg(stmt, args, kwargs, 0, "n"), "n", range(2 * len(prefixes)))
        return float(runner.robot.values.get(f"{prefixes[n // 2]}{n % 2}", 0.0))

    return read


for _group in ("standard", "configurable", "tool"):
    IO[f"get_{_group}_digital_in"] = _digital(_group, "actual_digital_input_bits")
    IO[f"get_{_group}_digital_out"] = _digital(_group, "actual_digital_output_bits")
IO["get_digital_in"] = _deprecated_digital("actual_digital_input_bits")
IO["get_digital_out"] = _deprecated_digital("actual_digital_output_bits")
IO["get_standard_analog_in"] = _analog(("standard_analog_input",))
IO["get_standard_analog_out"] = _analog(("standard_analog_output",))
IO["get_tool_analog_in"] = _analog(("tool_analog_input",))
IO["get_analog_in"] = _analog(("standard_analog_input", "tool_analog_input"))
IO["get_analog_out"] = _analog(("standard_analog_output",))
