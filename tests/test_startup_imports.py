"""What each CLI path imports (issue 21.5, instant start): no path imports pandas, and
models and the spec's meta-model are imported when first used, not up front.

Each path runs as a user runs it, in a fresh interpreter, through `cli.main.main`; a
small wrapper writes `sys.modules` when it ends. Counting imports, not timing them,
keeps the test exact on a loaded machine (benchmarks/startup.py has the times).
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.wire.fields import wire_field, wire_primitives
from tests.capture_files import rtde_capture, rtde_packages

WRAPPER = """
import json, sys
from rtde_spec.cli.main import main
try:
    code = main(sys.argv[2:])
finally:
    with open(sys.argv[1], "w") as f:
        json.dump(sorted(sys.modules), f)
raise SystemExit(code)
"""

META_MODEL = "rtde_spec.metamodel.schema"  # the pydantic meta-model: codegen's validator of spec/
PRIMARY_MODELS = "rtde_spec._generated.primary_models"
SPEC_FILES = ("yaml", "rtde_spec.metamodel.dashboard", "rtde_spec.metamodel.external")  # their meta-models
RTDE_MODELS = "rtde_spec._generated.rtde_models"  # the ~100 pydantic package models
RTDE_ONLY = (META_MODEL, PRIMARY_MODELS, "construct", *SPEC_FILES)


def run_cli(cwd: Path, *args: str) -> tuple[int, set[str], str]:
    """(exit code, modules loaded at exit, stderr) of `rtde-spec ARGS` in its own interpreter."""
    out = cwd / "modules.json"
    done = subprocess.run(
        [sys.executable, "-c", WRAPPER, str(out), *args], cwd=cwd, capture_output=True, text=True, timeout=600
    )
    return done.returncode, set(json.loads(out.read_text())), done.stderr


def closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def one_package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """An RTDE session's setup and one data package."""
    return rtde_capture(tmp_path_factory.mktemp("pcap") / "one.pcap", rtde_packages(1))


def test_help_imports_no_models_numpy_or_arrow(tmp_path: Path) -> None:
    code, modules, _ = run_cli(tmp_path, "--help")
    assert code == 0
    heavy = {"pandas", "pydantic", "numpy", "pyarrow", "construct", "yaml", META_MODEL}
    assert not heavy & modules


@pytest.mark.parametrize("fmt", ["parquet", "csv", "jsonl"])
def test_capture_of_rtde_imports_no_pandas_meta_model_or_primary_models(
    tmp_path: Path, one_package: Path, fmt: str
) -> None:
    out = str(tmp_path / "out")
    code, modules, err = run_cli(tmp_path, "capture", str(one_package), "-o", out, "--format", fmt)
    assert code == 0, err
    assert list((tmp_path / "out").rglob(f"*.{fmt}")), "the tables were written"
    assert "pandas" not in modules
    setup = [p for p in (tmp_path / "out").rglob(f"*.{fmt}") if "rtde_setup" in str(p)]
    assert len(setup) == 1, "the setup packages were decoded..."
    if fmt == "parquet":
        import pyarrow.parquet as pq

        packages = pq.read_table(setup[0]).column("package").to_pylist()
        assert "setup_outputs_v2_reply" in packages and len(packages) == 6, packages
    else:
        assert b"setup_outputs_v2_reply" in setup[0].read_bytes()
    # ...by the layout engine alone: no pydantic (neither the package models nor the meta-model),
    # no primary models, construct or YAML
    assert not {*RTDE_ONLY, "pydantic", RTDE_MODELS} & modules
    assert not [m for m in modules if m.startswith("rtde_spec.primary")]  # nor any of the primary interface


def test_decode_imports_no_pandas_or_meta_model(tmp_path: Path) -> None:
    from rtde_spec import build

    hexes = build("request_protocol_version_reply", accepted=True).hex()
    for extra in ([], ["--format", "json"], ["-o", str(tmp_path / "d.parquet")]):
        code, modules, err = run_cli(tmp_path, "decode", "--from", "controller", *extra, hexes)
        assert code == 0, err
        assert not {"pandas", META_MODEL, PRIMARY_MODELS, "construct"} & modules, extra
    assert (tmp_path / "d.parquet").stat().st_size > 0


def test_record_reaches_the_network_without_pandas_or_meta_model(tmp_path: Path) -> None:
    port = str(closed_port())
    args = ["record", "--host", "127.0.0.1", "--port", port, "--fields", "timestamp", "--timeout", "2"]
    code, modules, err = run_cli(tmp_path, *args, "-o", str(tmp_path / "r.csv"))
    assert code == 1 and "nothing accepts connections" in err, err
    assert not {"pandas", "pydantic", RTDE_MODELS, PRIMARY_MODELS, "construct"} & modules


def test_a_whole_recording_loads_no_pydantic(tmp_path: Path) -> None:
    """Version, controller version, setup, start and the data, against the emulator: the client's
    control path runs on the layout engine, so a recorder never loads pydantic."""
    from rtde_spec import EmulatorConfig, EmulatorThread

    emu = EmulatorThread(
        EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, realtime_port=None, dashboard_port=None)
    ).start()
    try:
        port = str(emu.ports["rtde"])
        args = ["record", "--host", "127.0.0.1", "--port", port, "--fields", "timestamp,actual_q"]
        code, modules, err = run_cli(tmp_path, *args, "--duration", "0.3", "-o", str(tmp_path / "r.csv"))
    finally:
        emu.stop()
    assert code == 0, err
    rows = (tmp_path / "r.csv").read_text().splitlines()
    assert rows[0].startswith("timestamp,actual_q_0") and len(rows) > 10, rows[:3]
    assert "controller 5.15" in err or "controller" in err
    assert not {"pandas", "pydantic", RTDE_MODELS, PRIMARY_MODELS, "construct", META_MODEL} & modules


def test_fields_and_validate_import_no_pandas(tmp_path: Path) -> None:
    code, modules, err = run_cli(tmp_path, "fields", "--controller", "5.15.0")
    assert code == 0, err
    assert not {"pandas", "pydantic", "numpy", META_MODEL} & modules
    code, modules, err = run_cli(tmp_path, "validate", "timestamp,actual_q", "--controller", "5.15.0")
    assert code == 0, err
    assert not {"pandas", META_MODEL} & modules


def _same_field(wire: Any, model: Any, where: str) -> None:
    """The runtime's field reads as the meta-model's, attribute by attribute, groups too."""
    for attr in ("name", "type", "count", "length", "fallback", "format", "repeat", "when", "switch",
                 "group", "enum", "unit", "scale", "kind"):  # fmt: skip
        assert getattr(wire, attr) == getattr(model, attr), f"{where}.{attr}"
    wire_cases, model_cases = wire.cases, model.cases
    assert (wire_cases is None) == (model_cases is None), where
    for key, case in (model_cases or {}).items():
        other = wire_cases[key]
        same = (
            other == case if isinstance(case, str) else (other.type, other.length) == (case.type, case.length)
        )
        assert same, f"{where} case {key}"
    wire_inner, model_inner = wire.fields, model.fields
    assert (wire_inner is None) == (model_inner is None), where
    assert len(wire_inner or ()) == len(model_inner or ()), where
    for a, b in zip(wire_inner or (), model_inner or (), strict=True):
        _same_field(a, b, f"{where}.{b.name}")


def test_runtime_fields_read_as_the_meta_model_does() -> None:
    """Decoding builds its layouts from the generated dicts without pydantic (wire.fields);
    every field of every RTDE package, primary message and external-control record reads as
    the validated spec's."""
    from rtde_spec._generated.external_control import EXTERNAL_CONTROL
    from rtde_spec._generated.spec_data import SPEC
    from rtde_spec.metamodel.schema import LayoutField, Primitive

    fields = [(m["name"], f) for m in SPEC["packages"]["messages"] for f in m.get("fields", [])]
    for fam in SPEC["primary"]["families"]:
        fields += [(fam["name"], f) for f in fam.get("prefix", [])]
        for member in fam.get("members", []):
            fields += [(member["name"], f) for f in member["fields"]]
            fields += [(member["name"], f) for old in member.get("older", []) for f in old["fields"]]
    for proto in EXTERNAL_CONTROL["protocols"]:
        for msg in proto.get("messages", []):
            for record in [msg, *msg.get("older", [])]:
                fields += [(v["name"], f) for v in record["variants"] for f in v["fields"]]
    assert len(fields) > 250
    assert any("scale" in f for _, f in fields)
    assert any("cases" in f for _, f in fields) and any("fields" in f for _, f in fields)
    for where, data in fields:
        _same_field(wire_field(data), LayoutField.model_validate(data), f"{where}.{data['name']}")
    prims = SPEC["primitives"]["primitives"]
    for name, prim in wire_primitives(prims).items():
        model = Primitive.model_validate(next(p for p in prims if p["name"] == name))
        assert (prim.size, prim.struct, prim.kind, prim.signed, prim.bounds) == (
            model.size, model.struct, model.kind, model.signed, model.bounds
        ), name  # fmt: skip


def test_the_primary_codec_from_generated_data_is_the_one_from_the_validated_spec() -> None:
    """default_codec reads the generated data (no meta-model); a validated Spec gives the same codec."""
    from rtde_spec.metamodel.catalogue import Catalogue
    from rtde_spec.primary.codec import PrimaryCodec, default_codec

    plain, validated = default_codec(), PrimaryCodec(Catalogue.builtin().spec)
    assert plain.families.keys() == validated.families.keys()
    for mtype, fam in plain.families.items():
        other = validated.families[mtype]
        assert (fam.spec.name, fam.spec.layout, fam.spec.tag) == (
            other.spec.name,
            other.spec.layout,
            other.spec.tag,
        )
        assert fam.members.keys() == other.members.keys()
        for key, (cls, layout) in fam.members.items():
            assert cls is other.members[key][0] and layout.names == other.members[key][1].names
            assert layout.fixed_size == other.members[key][1].fixed_size
        assert {t: [v for v, _ in r] for t, r in fam.older.items()} == {
            t: [v for v, _ in r] for t, r in other.older.items()
        }
    assert plain.field_since == validated.field_since and plain.field_since
    assert (plain.header.format, plain.sub_header.format, plain.max_size) == (
        validated.header.format, validated.sub_header.format, validated.max_size
    )  # fmt: skip
    assert plain.values.by_name.keys() == validated.values.by_name.keys()


@pytest.mark.parametrize("fmt", ["parquet", "csv", "jsonl"])
def test_capture_of_the_primary_interface_imports_no_pandas(tmp_path: Path, fmt: str) -> None:
    """Primary messages carry UINT64s (numpy scalars in the rows), which pyarrow's own
    conversion would read by importing pandas: the table builder must not hand them to it."""
    from rtde_spec.examples import primary_stream
    from tests.capture_files import Conversation, write

    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30001))
    conv.handshake()
    conv.send("server", primary_stream())
    pcap = write(tmp_path / "primary.pcap", [conv])
    code, modules, err = run_cli(tmp_path, "capture", str(pcap), "-o", str(tmp_path / "out"), "--format", fmt)
    assert code == 0, err
    tables = {p.parent.parent.parent.name for p in (tmp_path / "out").rglob(f"*.{fmt}")}
    assert len(tables) > 10 and "primary_robot_mode_data" in tables, tables
    assert "pandas" not in modules


def test_plot_of_a_capture_folder_imports_no_pandas(tmp_path: Path, one_package: Path) -> None:
    """pyarrow.dataset imports pandas; a hive folder of our own is read without it (output/hive.py)."""
    out = tmp_path / "out"
    code, _, err = run_cli(tmp_path, "capture", str(one_package), "-o", str(out))
    assert code == 0, err
    code, modules, err = run_cli(tmp_path, "plot", str(out), "timestamp", "-o", str(tmp_path / "p.png"))
    assert code == 0, err
    assert (tmp_path / "p.png").stat().st_size > 1000
    assert "pandas" not in modules and "pyarrow._dataset" not in modules


BLAS_THREADS = """
import os, sys
os.environ.pop("OPENBLAS_NUM_THREADS", None)
if len(sys.argv) > 1:
    os.environ["OPENBLAS_NUM_THREADS"] = sys.argv[1]
import rtde_spec.cli.main
import numpy
print(os.environ["OPENBLAS_NUM_THREADS"], len(os.listdir("/proc/self/task")))
"""


@pytest.mark.skipif(not Path("/proc/self/task").is_dir(), reason="threads are counted in Linux's /proc")
def test_a_command_loads_numpy_without_openblas_threads_spinning() -> None:
    """OpenBLAS starts a thread per core when numpy loads, which spins ~0.1 s of CPU at every
    start; the CLI asks for one (and keeps a user's own setting)."""
    run = [sys.executable, "-c", BLAS_THREADS]
    assert subprocess.run(run, capture_output=True, text=True, check=True).stdout.split() == ["1", "1"]
    mine = subprocess.run([*run, "2"], capture_output=True, text=True, check=True).stdout.split()
    assert mine[0] == "2"
