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
