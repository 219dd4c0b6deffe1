"""How tests/data/import/pdf_*.txt were made: the e-Series guide's field rows (the shared seed,
read by the importer) as a printed page (narrow name column, so names wrap at their `_`, the
table's header repeated on every page, a running title and "Page N of M"), rendered to PDF by
WeasyPrint and turned back to text by poppler's `pdftotext`, plain and `-layout`.

    pip install weasyprint   # and apt-get install poppler-utils
    python tests/data/import/make_pdf_text.py OUT_DIR [--full]

Without --full, a few rows of each table on small pages (the committed fixtures); with it, the
whole guide (what tests/test_spec_import_pdf_text.py's notes were checked on). Not run by the tests.
"""

from __future__ import annotations

import html
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
SEED = ROOT.parent / "shared" / "seeds" / "rtde-guide-e-series-era.txt"
#: the rows of the small fixtures: wrapped names, a family, versions, empty comments, a page break
FEW = {
    "input": ["speed_slider_mask", "standard_digital_output_mask", "input_bit_registers0_to_31",
              "input_int_register_X", "external_force_torque"],
    "output": ["timestamp", "actual_q", "actual_current_as_torque", "actual_TCP_acceleration",
               "robot_mode", "safety_mode", "actual_joint_voltage", "actual_configurable_digital_output_bits",
               "output_int_register_X", "payload_cog", "script_control_line", "target_base_acceleration"],
}  # fmt: skip
CSS = """
@page { size: %s; margin: 1.5cm;
        @top-center { content: "Real-Time Data Exchange (RTDE) Guide"; font-size: 8pt }
        @bottom-center { content: "Page " counter(page) " of " counter(pages); font-size: 8pt } }
body { font-family: sans-serif; font-size: 9pt }
table { border-collapse: collapse; width: 100%%; table-layout: fixed }
td, th { border: 1px solid #888; padding: 4pt 8pt; vertical-align: top; text-align: left }
col.n { width: 22%% } col.t { width: 12%% } col.c { width: 48%% } col.v { width: 18%% }
"""


def seed_rows() -> dict[str, list[list[str]]]:
    sys.path.insert(0, str(ROOT))
    from rtde_spec.importers import read_document
    from rtde_spec.metamodel.loader import load_spec

    doc = read_document(SEED, load_spec(ROOT / "spec"))
    rows: dict[str, list[list[str]]] = {"input": [], "output": []}
    for f in doc.fields:
        version = f.version_text or " ".join(" / ".join(n.versions.values()) for n in f.notes)
        rows[f.direction].append([f.name.replace("{X}", "X"), f.type, f.doc, version])
    return rows


def page(rows: dict[str, list[list[str]]], size: str) -> str:
    """The guide's tables as HTML; `<wbr>` after each `_`, where a narrow cell may break a name."""
    out = [
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><style>{CSS % size}</style></head><body>",
        "<h1>Real-Time Data Exchange (RTDE) Guide</h1>",
        "<h2>Field Names and Associated Types</h2>",
    ]
    for direction, heading in (("input", "Robot Controller Inputs"), ("output", "Robot Controller Outputs")):
        out.append(
            f"<h3>{heading}</h3><table><colgroup><col class=n><col class=t><col class=c><col class=v>"
            "</colgroup><thead><tr><th>Name</th><th>Type</th><th>Comment</th><th>Introduced in version</th>"
            "</tr></thead><tbody>"
        )
        for name, type_, comment, version in rows[direction]:
            shown = html.escape(name).replace("_", "_<wbr>")
            out.append(
                f"<tr><td>{shown}</td><td>{type_}</td><td>{html.escape(comment)}</td>"
                f"<td>{html.escape(version)}</td></tr>"
            )
        out.append("</tbody></table>")
    out.append("<h2>Data types</h2><p>The data types of the fields are sent in network byte order.</p>")
    return "\n".join([*out, "</body></html>"])


def main() -> None:
    out_dir = Path(sys.argv[1])
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = seed_rows()
    if "--full" not in sys.argv:
        rows = {d: [r for r in rows[d] if r[0] in FEW[d]] for d in rows}
    size = "A4" if "--full" in sys.argv else "A5"
    (out_dir / "guide.html").write_text(page(rows, size), encoding="utf-8")
    subprocess.run(["weasyprint", out_dir / "guide.html", out_dir / "guide.pdf"], check=True)
    subprocess.run(["pdftotext", out_dir / "guide.pdf", out_dir / "pdf_plain.txt"], check=True)
    subprocess.run(["pdftotext", "-layout", out_dir / "guide.pdf", out_dir / "pdf_layout.txt"], check=True)


if __name__ == "__main__":
    main()
