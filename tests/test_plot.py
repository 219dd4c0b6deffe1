"""`rtde-spec plot` on what `capture` writes: the output folder, one table, several robots."""

from __future__ import annotations

from pathlib import Path

from rtde_spec.capture.decoder import decode_to_directory

from .capture_files import Conversation, write
from .test_capture import data, session
from .test_cli import cli

PNG = b"\x89PNG\r\n\x1a\n"


def capture_folder(tmp_path: Path, robots: tuple[str, ...] = ("10.0.0.10",)) -> Path:
    """`capture -o out` of one session per robot: out/rtde_outputs_1, out/rtde_setup, ..."""
    conversations = []
    for k, robot in enumerate(robots):
        conv = Conversation((f"10.0.0.{50 + k}", 51000 + k), (robot, 30004))
        session(conv)
        for i in range(40):
            conv.send("server", data(i + 100 * k))
        conversations.append(conv)
    out = tmp_path / "out"
    decode_to_directory(write(tmp_path / "robots.pcap", conversations), out)
    return out


def test_the_output_folder_of_a_capture_plots_the_table_holding_the_fields(tmp_path: Path) -> None:
    out = capture_folder(tmp_path)
    png = tmp_path / "q.png"
    result = cli("plot", str(out), "actual_q", "-o", str(png))
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:8] == PNG
    assert "Traceback" not in result.stderr


def test_a_field_no_table_has_names_the_tables_and_writes_nothing(tmp_path: Path) -> None:
    out = capture_folder(tmp_path)
    png = tmp_path / "q.png"
    png.write_bytes(b"old image")
    result = cli("plot", str(out), "no_such_field", "-o", str(png))
    assert result.returncode == 2
    assert "rtde_outputs_1" in result.stderr and "--table" in result.stderr
    assert "Traceback" not in result.stderr and "pyarrow" not in result.stderr
    assert png.read_bytes() == b"old image"  # a failed run leaves the old file alone
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_an_unknown_table_name_lists_the_ones_there(tmp_path: Path) -> None:
    out = capture_folder(tmp_path)
    result = cli("plot", str(out), "actual_q", "--table", "rtde_outputs_9", "-o", str(tmp_path / "q.png"))
    assert result.returncode == 2 and "rtde_outputs_1" in result.stderr


def test_a_dataset_of_several_robots_plots_one_line_set_per_robot(tmp_path: Path) -> None:
    from rtde_spec.cli.plot_cmd import load, split_robots

    out = capture_folder(tmp_path, robots=("10.0.0.10", "10.0.0.11"))
    per_robot = split_robots(load(out / "rtde_outputs_1"), None)
    assert sorted(per_robot) == ["10.0.0.10", "10.0.0.11"]
    assert all(len(cols["timestamp"]) == 40 for cols in per_robot.values())
    assert all("robot" not in cols for cols in per_robot.values())
    png = tmp_path / "q.png"
    result = cli("plot", str(out), "actual_q", "robot_mode", "-o", str(png))
    assert result.returncode == 0, result.stderr
    one = cli("plot", str(out), "actual_q", "--robot", "10.0.0.11", "-o", str(png))
    assert one.returncode == 0, one.stderr
    nobody = cli("plot", str(out), "actual_q", "--robot", "10.9.9.9", "-o", str(png))
    assert nobody.returncode == 2 and "10.0.0.10" in nobody.stderr


def test_a_file_that_is_not_parquet_is_a_clear_error(tmp_path: Path) -> None:
    bad = tmp_path / "bad.parquet"
    bad.write_bytes(b"PAR1 this is not a parquet file")
    result = cli("plot", str(bad), "actual_q", "-o", str(tmp_path / "q.png"))
    assert result.returncode == 1 and "bad.parquet" in result.stderr and "Traceback" not in result.stderr


def test_cells_that_are_not_numbers_are_said_with_their_lines_and_exit_3(tmp_path: Path) -> None:
    """A truncated CSV (its last row cut short) or a garbled cell was plotted as a gap with no
    word, exit 0. The plot is still written; stderr names each line, the exit code is 3. A
    column of text alone (a name, a mode word) is no fault."""
    table = tmp_path / "run.csv"
    rows = [f"{i / 500},{0.1 * i},{-0.1 * i},RUNNING" for i in range(20)]
    rows[7] = "0.014,abc,-0.7,RUNNING"
    table.write_text("timestamp,actual_q_0,actual_q_1,mode\n" + "\n".join(rows) + "\n0.04,2.0")
    image = tmp_path / "q.png"
    done = cli("plot", str(table), "actual_q", "-o", str(image))
    assert done.returncode == 3, done.stderr
    assert image.stat().st_size > 0
    assert "problem: line 22: cut short (2 of 4 cells)" in done.stderr, done.stderr
    assert "problem: column actual_q_0: 1 cell not numbers (line 9 'abc')" in done.stderr, done.stderr
    assert "mode" not in done.stderr
    whole = [r for i, r in enumerate(rows) if i != 7]
    table.write_text("timestamp,actual_q_0,actual_q_1,mode\n" + "\n".join(whole))
    done = cli("plot", str(table), "actual_q", "-o", str(image))
    assert done.returncode == 0 and "problem" not in done.stderr, done.stderr


RECORDED = ["timestamp", "actual_q", "robot_mode", "actual_digital_input_bits"]


def _ur_record_files(tmp_path: Path, rows: int) -> tuple[Path, Path, list[dict[str, object]]]:
    """What UR's examples/record.py writes for RECORDED: its CSV (cells separated by spaces) and its
    --binary form (names, types with a vector's type once per component, then each package's field
    bytes as sent, without header and recipe id)."""
    from rtde_spec import RecipeCodec
    from rtde_spec.recipes.codec import PAYLOAD_OFFSET

    codec = RecipeCodec.for_names(RECORDED, "output")
    values = [
        {"timestamp": 1.5 + i * 0.008, "actual_q": tuple(0.1 * i + j for j in range(6)), "robot_mode": 7,
         "actual_digital_input_bits": 2**40 + i}
        for i in range(rows)
    ]  # fmt: skip
    names = ["timestamp", *(f"actual_q_{j}" for j in range(6)), "robot_mode", "actual_digital_input_bits"]
    types = ["DOUBLE"] * 7 + ["INT32", "UINT64"]
    text = tmp_path / "robot_data.csv"
    lines = [" ".join(names)]
    lines += [
        " ".join(map(str, [v["timestamp"], *v["actual_q"], 7, v["actual_digital_input_bits"]]))
        for v in values
    ]
    text.write_text("\r\n".join(lines) + "\r\n")  # csv.writer ends rows with CRLF
    binary = tmp_path / "robot_data.bin"
    body = b"".join(codec.encode_package(v, recipe_id=1)[PAYLOAD_OFFSET:] for v in values)
    binary.write_bytes(f"{' '.join(names)}\n{' '.join(types)}\n".encode() + body)
    return text, binary, values


def test_ur_record_py_recordings_plot_in_both_its_forms(tmp_path: Path) -> None:
    """UR's own client records with record.py, whose CSV separates cells by spaces and whose binary
    form is its own: plot read the CSV's header as one column ("no time column") and the binary
    file as text. Both now give the recorded values; a binary row cut short is said, exit 3."""
    from rtde_spec.cli.plot_cmd import load

    text, binary, values = _ur_record_files(tmp_path, 25)
    for path in (text, binary):
        columns = load(path)
        assert columns["timestamp"] == [v["timestamp"] for v in values]
        assert columns["actual_q_5"] == [v["actual_q"][5] for v in values]  # type: ignore[index]
        assert columns["actual_digital_input_bits"] == [v["actual_digital_input_bits"] for v in values]
        assert columns["robot_mode"] == [7] * 25
        image = tmp_path / f"{path.suffix[1:]}.png"
        done = cli("plot", str(path), "actual_q", "robot_mode", "-o", str(image))
        assert done.returncode == 0 and image.read_bytes().startswith(PNG), done.stderr
    binary.write_bytes(binary.read_bytes()[:-10])
    problems: list[str] = []
    assert len(load(binary, problems)["timestamp"]) == 24
    assert problems == [
        f"byte {binary.stat().st_size - 58}: the last row is cut short (58 of 68 bytes): dropped"
    ]
    done = cli("plot", str(binary), "actual_q", "-o", str(tmp_path / "cut.png"))
    assert done.returncode == 3 and "the last row is cut short" in done.stderr, done.stderr


def test_a_table_given_to_decode_or_capture_is_named_with_the_command_that_reads_it(tmp_path: Path) -> None:
    """A recording (UR's record.py CSV or binary, our own Parquet) given to `decode` was decoded
    as packages ("unknown package type 109 ('m')") and to `capture` was "not a pcap (magic
    74696d65)". Each now says what the file is and that `plot` draws it; a client's session whose
    setup names four fields between binary bytes is still packages."""
    from rtde_spec import build
    from rtde_spec.output.ur_recordings import recording_kind

    text, binary, _ = _ur_record_files(tmp_path, 5)
    parquet = tmp_path / "run.parquet"
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    pq.write_table(pacsv.read_csv(text, parse_options=pacsv.ParseOptions(delimiter=" ")), parquet)
    for path, kind in ((text, "a recorded table (CSV)"), (binary, "a binary recording of UR's record.py"),
                       (parquet, "a Parquet table")):  # fmt: skip
        for command in ("decode", "capture"):
            done = cli(command, str(path), *(["-o", str(tmp_path / "out")] if command == "capture" else []))
            assert done.returncode == 2, done.stderr
            assert f"this is {kind}, a table already: `rtde-spec plot {path} FIELD" in done.stderr
    names = ["timestamp", "actual_q", "robot_mode", "safety_mode"]
    session = build("setup_outputs_v2", output_frequency=125.0, variable_names=names) + build("start")
    assert recording_kind(session) is None
