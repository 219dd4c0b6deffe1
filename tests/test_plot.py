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
