"""The rtde-spec command line, run as a user runs it (a real subprocess)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from .helpers import golden


def cli(*args: str, stdin: bytes | None = None) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("rtde-spec")
    cmd = [exe] if exe else [sys.executable, "-m", "rtde_spec.cli"]
    return subprocess.run(
        [*cmd, *args],
        capture_output=True,
        text=True,
        input=None if stdin is None else stdin.decode("latin-1"),
    )


def test_decode_protocol_version_reply() -> None:
    result = cli("decode", "00045601", "--from", "controller")
    assert result.returncode == 0
    assert "request_protocol_version_reply" in result.stdout
    assert "accepted" in result.stdout and "True" in result.stdout


def test_decode_json_keys_are_spec_field_names() -> None:
    result = cli("decode", "00045601", "--from", "controller", "--json")
    assert json.loads(result.stdout)[0]["accepted"] is True
    result = cli("decode", "0013 76 00000005 0000000c 00000002 00002a3b", "--json")
    (record,) = json.loads(result.stdout)
    assert (record["major"], record["minor"], record["bugfix"], record["build"]) == (
        5,
        12,
        2,
        10811,
    )


def test_decode_json_is_one_array_whatever_the_number_of_packages() -> None:
    """One shape for a script to rely on: a list of objects, for 0, 1 or many packages."""
    reply = "00045601"
    for count in (1, 2, 5):
        for protocol, data in (("rtde", reply * count), ("primary", None)):
            if protocol == "primary":
                import yaml

                from .helpers import DATA

                golden = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
                version = next(c for c in golden if c["message"] == "version_message")["hex"]
                data = version * count
            result = cli("decode", "--protocol", protocol, str(data), "--format", "json")
            assert result.returncode == 0, result.stderr
            rows = json.loads(result.stdout)
            assert isinstance(rows, list) and len(rows) == count and all(isinstance(r, dict) for r in rows)
    assert "always one array" in cli("decode", "--help").stdout


def test_decode_several_packages_from_a_binary_file(tmp_path: Path) -> None:
    cases = [c for c in golden() if c["sender"] == "client" and c["protocol"] == 2]
    path = tmp_path / "client.bin"
    path.write_bytes(b"".join(bytes.fromhex(c["hex"].replace(" ", "")) for c in cases))
    result = cli("decode", str(path), "--from", "client", "--json")
    assert result.returncode == 0, result.stderr
    records = json.loads(result.stdout)
    assert [r["package"] for r in records] == [c["package"] for c in cases]


def test_decode_protocol_1_layout() -> None:
    result = cli("decode", "0007 4d 01 626164", "--protocol-version", "1", "--json")
    assert json.loads(result.stdout)[0]["message"] == "bad"


def test_decode_errors_exit_non_zero_with_error_line() -> None:
    for bad in ("0002", "000956", "zz", "0004ff01"):
        result = cli("decode", bad)
        assert result.returncode != 0, bad
        assert result.stderr.startswith("error: "), result.stderr
        assert "Traceback" not in result.stderr


def test_fields_json_lists_expanded_registers() -> None:
    result = cli("fields", "--json")
    fields = json.loads(result.stdout)
    assert all({"name", "type"} <= set(f) for f in fields)
    names = {(f["direction"], f["name"]) for f in fields}
    assert ("output", "output_int_register_47") in names
    assert ("input", "input_bit_register_127") in names


def test_fields_for_a_controller_and_direction() -> None:
    old = {f["name"] for f in json.loads(cli("fields", "--controller", "3.15.8", "--json").stdout)}
    new = {f["name"] for f in json.loads(cli("fields", "--controller", "5.26.0", "--json").stdout)}
    assert "target_gravity" in new and "target_gravity" not in old
    ins = json.loads(cli("fields", "--direction", "input", "--json").stdout)
    assert {f["direction"] for f in ins} == {"input"}
    table = cli("fields", "--controller", "10.11.0")
    assert table.returncode == 0 and "actual_current_as_torque" in table.stdout


def test_fields_bad_controller() -> None:
    result = cli("fields", "--controller", "4.0.0")
    assert result.returncode == 2 and "no known product line" in result.stderr


def test_demo_decodes_the_embedded_session() -> None:
    result = cli("demo", "--offline")
    assert result.returncode == 0, result.stderr
    assert "data_package" in result.stdout and "actual_q=" in result.stdout
    assert "5.12.2" in result.stdout
    assert "3 messages (controller 5.15.0)" in result.stdout  # primary stream in 100-byte reads
    assert "13 sub-packages" in result.stdout
    lines = {line.split()[0]: line for line in result.stdout.splitlines() if line[:2] in ("3.", "5.", "10")}
    assert "INVALID" in lines["3.15.8"] and "ft_raw_wrench" in lines["3.15.8"]
    assert "valid" in lines["5.12.2"] and "INVALID" not in lines["5.12.2"]


def test_benchmark_recipe_is_the_shipped_example() -> None:
    import importlib.util
    from importlib import resources

    from .helpers import ROOT

    spec = importlib.util.spec_from_file_location("bench", ROOT / "benchmarks/bench_recipe_decode.py")
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    text = resources.files("rtde_spec.examples").joinpath("ur_rtde_default_outputs.txt").read_text()
    shipped = [n for n in text.splitlines() if n and not n.startswith("#")]
    assert bench.UR_RTDE_DEFAULT_OUTPUTS == shipped and len(shipped) == 58


def test_validate_valid_invalid_and_usage_exit_codes(tmp_path: Path) -> None:
    ok = cli("validate", "timestamp,actual_q", "--controller", "5.12.2", "--frequency", "500")
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "name" in ok.stdout and "available since" in ok.stdout and "valid" in ok.stdout
    bad = cli("validate", "timestamp,safety_status", "--controller", "3.9.0")
    assert bad.returncode == 1
    assert "available from 3.10.0" in bad.stdout
    assert cli("validate", "missing.xml").returncode == 2
    assert cli("validate", "timestamp", "--controller", "4.0.0").returncode == 2
    assert cli("validate", "timestamp", "--frequency", "fast").returncode == 2
    assert cli("validate").returncode == 2


def test_validate_json_and_xml_file() -> None:
    from .helpers import DATA

    result = cli("validate", str(DATA / "ur_client_config.xml"), "--controller", "5.12.2", "--json")
    assert result.returncode == 0, result.stdout
    report = json.loads(result.stdout)
    assert report["valid"] is True and report["line"] == "e-series"
    keys = [r["key"] for r in report["recipes"]]
    assert keys == ["state", "setp", "watchdog"]
    assert report["recipes"][0]["answer"] == ["DOUBLE", "VECTOR6D", "INT32", "INT32"]
    assert any(p["code"] == "reserved" for p in report["recipes"][0]["problems"]) is False


def test_validate_direction_flag() -> None:
    result = cli(
        "validate", "input_int_register_30", "--direction", "output", "--json", "--controller", "5.12.2"
    )
    assert json.loads(result.stdout)["recipes"][0]["direction"] == "output"


def test_decode_data_package_with_a_recipe() -> None:
    from rtde_spec.recipes.codec import RecipeCodec

    names = ["timestamp", "robot_mode", "actual_q"]
    codec = RecipeCodec.for_names(names, "output")
    package = codec.encode_package({"timestamp": 2.5, "robot_mode": 7, "actual_q": (1.0,) * 6}, 1)
    result = cli("decode", package.hex(), "--recipe", ",".join(names), "--json")
    (record,) = json.loads(result.stdout)
    assert (record["timestamp"], record["robot_mode"], record["actual_q"]) == (2.5, 7, [1.0] * 6)
    table = cli("decode", package.hex(), "--recipe", ",".join(names))
    assert "7 (RUNNING)" in table.stdout
    short = cli(
        "decode", package[:-8].hex().replace(package[:2].hex(), "0033", 1), "--recipe", ",".join(names)
    )
    assert short.returncode == 1 and "error: " in short.stderr


def test_decode_primary_messages(tmp_path: Path) -> None:
    import yaml

    from .helpers import DATA

    golden = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
    version = next(c for c in golden if c["message"] == "version_message")
    joints = next(c for c in golden if c["message"] == "joint_data")
    path = tmp_path / "primary.bin"
    path.write_bytes(bytes.fromhex(version["hex"]) + bytes.fromhex(joints["hex"]))
    result = cli("decode", "--protocol", "primary", str(path), "--json")
    assert result.returncode == 0, result.stderr
    first, second = json.loads(result.stdout)
    assert first["package"] == "version_message" and first["project_name"] == "URControl"
    sub = second["sub_packages"][0]
    assert sub["package"] == "joint_data" and sub["joints"][5]["joint_mode"] == 253
    table = cli("decode", "--protocol", "primary", str(path))
    assert "joint_mode: 253 (RUNNING)" in table.stdout
    assert "controller version (from the version message): 5.15.0" in table.stdout
    bad = cli("decode", "--protocol", "primary", "0000000a1000000003")
    assert bad.returncode == 1 and bad.stderr.startswith("error: ")
