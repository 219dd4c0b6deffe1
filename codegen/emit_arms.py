"""Emit _generated/arms.py and docs/reference/arms.md from spec/arms/models.yaml.

The arm file is separate from the protocol spec (it describes hardware, not the
wire), so it has its own meta-model (rtde_spec.metamodel.arms) and its own emitter.
"""

from __future__ import annotations

import math

from rtde_spec.metamodel.arms import ArmsFile

from .render import GEN, MD_HEADER, literal_module, md_table


def emit_arms(arms: ArmsFile) -> dict[str, str]:
    """Relative output path -> text, for the arm models of the loaded spec."""
    return {f"{GEN}/arms.py": _python(arms), "docs/reference/arms.md": _markdown(arms)}


def _python(arms: ArmsFile) -> str:
    return literal_module(
        "UR arm models of spec/arms/models.yaml: nominal DH rows, limits, payload, reach.",
        "ARMS",
        arms.model_dump(mode="json"),
    )


def _angle(value: float) -> str:
    """alpha as a multiple of pi/2 where it is one (it always is for UR arms)."""
    quarter = value / (math.pi / 2)
    if abs(quarter - round(quarter)) < 1e-12:
        return {0: "0", 1: "π/2", -1: "-π/2", 2: "π", -2: "-π"}.get(round(quarter), f"{value:g}")
    return f"{value:g}"


def _markdown(arms: ArmsFile) -> str:
    out = [
        MD_HEADER,
        "# Arm models\n\n",
        "Nominal kinematics of each Universal Robots arm, as the emulator's forward and inverse\n",
        "kinematics and its kinematics sub-package use them (`serve --model NAME`). Standard\n",
        "Denavit-Hartenberg rows, theta offsets 0; frame 0 is the controller's Base frame and\n",
        "frame 6 the tool flange. Lengths in m, alpha in rad; ranges ± degrees; speeds deg/s.\n",
        "A real arm adds its own calibration to these values.\n\n",
    ]
    rows = [
        (
            m.name,
            m.line,
            m.payload_kg,
            m.reach_m,
            ", ".join(f"{v:g}" for v in m.joint_speed_deg_s) if m.joint_speed_deg_s else "not published here",
            "yes" if m.checked else "no",
        )
        for m in arms.models
    ]
    out.append(md_table(["model", "line", "payload kg", "reach m", "joint speeds deg/s", "DH checked"], rows))
    for m in arms.models:
        out.append(f"\n## {m.name}\n\n{m.doc}\n\nSource: {m.source}\n\n")
        columns = zip(m.dh.a, m.dh.d, m.dh.alpha, m.joint_range_deg, strict=True)
        dh = [(i + 1, f"{a:g}", f"{d:g}", _angle(al), f"±{r:g}") for i, (a, d, al, r) in enumerate(columns)]
        out.append(md_table(["joint", "a [m]", "d [m]", "alpha [rad]", "range [deg]"], dh))
    return "".join(out)
