"""The text URScript makes of a value (`to_str`, `str_cat`, `textmsg`, `popup`,
`socket_send_string`): a pose shows as the manual writes one, `p[x, y, z, rx, ry, rz]`, and a
list of poses shows each as a pose; a joint list stays a plain `[...]`."""

from __future__ import annotations

from .test_urscript_control import run


def said(script: str, steps: int = 50) -> list[str]:
    """What the program says (textmsg and popup), stepped as the server steps it."""
    _, events = run(script, steps)
    assert not [text for kind, text, _, _ in events if kind == "runtime_exception"]
    return [text for kind, text, _, _ in events if kind in ("text", "popup")]


def test_a_pose_shows_as_p_and_its_six_numbers() -> None:
    lines = said(
        "def prog():\n"
        "  x = p[0.1, -0.2, 0.3, 0, 3.14159, 0]\n"
        "  textmsg(to_str(x))\n"
        "  textmsg(x)\n"
        '  textmsg("at ", x)\n'
        '  textmsg(str_cat("tcp: ", x))\n'
        "  textmsg(to_str([x, x]))\n"
        "  textmsg(to_str([0.1, -0.2, 0.3, 0, 3.14159, 0]))\n"
        "end\n"
    )
    pose = "p[0.1, -0.2, 0.3, 0, 3.14159, 0]"
    assert lines == [
        pose,
        pose,
        f"at {pose}",
        f"tcp: {pose}",
        f"[{pose}, {pose}]",
        "[0.1, -0.2, 0.3, 0, 3.14159, 0]",  # six numbers without p: joints, a plain list
    ]


def test_poses_the_arm_gives_show_as_poses() -> None:
    (line,) = said("def prog():\n  textmsg(get_actual_tcp_pose())\nend\n")
    assert line.startswith("p[") and line.count(",") == 5
