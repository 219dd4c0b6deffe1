"""Issue 18.6: recipe files cannot make loading take unbounded time or memory.

A 384-byte YAML recipe of nested aliases ("billion laughs") took over 60 s and
2.9 GB; aliases are refused now, as are YAML and JSON nested deeper than any recipe
and numbers Python will not convert. Each load runs in a child process under an
address-space limit and a time-out, so a regression fails instead of swapping.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

import rtde_spec

ROOT = Path(rtde_spec.__file__).resolve().parents[1]
LIMIT = 2 << 30
CHILD = r"""
import json, sys, time, tracemalloc
from rtde_spec.errors import RtdeSpecError
from rtde_spec.recipes.files import load_recipes
tracemalloc.start()
started = time.perf_counter()
out = {}
try:
    out["names"] = len(load_recipes(sys.argv[1])[0].names)
except RtdeSpecError as exc:
    out["error"] = str(exc)
    out["kind"] = type(exc).__name__
out["peak"] = tracemalloc.get_traced_memory()[1]
out["seconds"] = time.perf_counter() - started
print(json.dumps(out))
"""

BILLION_LAUGHS = """\
fields:
  - &a [actual_q,actual_q,actual_q,actual_q,actual_q,actual_q,actual_q,actual_q]
  - &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]
  - &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]
  - &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]
  - &e [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]
  - &f [*e,*e,*e,*e,*e,*e,*e,*e,*e,*e]
  - &g [*f,*f,*f,*f,*f,*f,*f,*f,*f,*f]
  - [*g,*g,*g,*g,*g,*g,*g,*g,*g,*g]
"""


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def load_in_child(path: Path, timeout: float = 60) -> dict[str, object]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    try:
        result = subprocess.run(
            [sys.executable, "-c", CHILD, str(path)],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
            preexec_fn=_limit,
        )
    except subprocess.TimeoutExpired:
        raise AssertionError(f"loading {path.name} took over {timeout} s") from None
    assert result.returncode == 0, result.stderr[-2000:]
    return json.loads(result.stdout)  # type: ignore[no-any-return]


def test_a_billion_laughs_yaml_recipe_is_refused_at_its_first_alias(tmp_path: Path) -> None:
    path = tmp_path / "laughs.yaml"
    path.write_text(BILLION_LAUGHS)
    assert len(BILLION_LAUGHS) < 400
    out = load_in_child(path)
    assert out.get("kind") == "RecipeError", out
    assert "aliases" in str(out["error"]) and "line 3" in str(out["error"]), out
    assert float(out["seconds"]) < 5 and int(out["peak"]) < 16 << 20, out


def test_yaml_and_json_nested_deeper_than_any_recipe_are_recipe_errors(tmp_path: Path) -> None:
    """200,000 open brackets: a RecursionError traceback in JSON, minutes in YAML, before."""
    for name in ("deep.json", "deep.yaml"):
        path = tmp_path / name
        path.write_text("[" * 200_000)
        out = load_in_child(path)
        assert out.get("kind") == "RecipeError", (name, out)
        assert "deep" in str(out["error"]), (name, out)
        assert float(out["seconds"]) < 10, (name, out)


def test_numbers_python_will_not_convert_are_recipe_errors(tmp_path: Path) -> None:
    """A 5,000-digit frequency: ValueError from int() (Python's digit limit) before."""
    for name, text in (
        ("big.yaml", "frequency: " + "9" * 5000 + "\nfields: [timestamp]\n"),
        ("big.json", '{"frequency": ' + "9" * 5000 + ', "fields": ["timestamp"]}'),
        ("word.yaml", "frequency: fast\nfields: [timestamp]\n"),
    ):
        path = tmp_path / name
        path.write_text(text)
        out = load_in_child(path)
        assert out.get("kind") == "RecipeError", (name, out)


def test_an_extra_fields_file_with_an_alias_is_refused_before_it_is_expanded(tmp_path: Path) -> None:
    from rtde_spec import Catalogue
    from rtde_spec.errors import SpecError

    bomb = tmp_path / "fields.yaml"
    bomb.write_text(
        "a: &a [1, 2]\n" + "".join(f"b{i}: &b{i} [*{'a' if i == 0 else f'b{i - 1}'}] \n" for i in range(3))
    )
    with pytest.raises(SpecError, match="aliases"):
        Catalogue.builtin().with_extra(bomb)
