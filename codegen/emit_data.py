"""Emit _generated/spec_data.py: the validated spec as a Python literal.

The runtime rebuilds the meta-model from it, so the installed package needs no
YAML files and answers exactly what spec/ said at generation time.
"""

from __future__ import annotations

import pprint

from rtde_spec.spec.schema import Spec

from .render import PY_HEADER


def emit_spec_data(spec: Spec) -> str:
    data = spec.model_dump(mode="json", exclude_defaults=True)
    literal = pprint.pformat(data, width=100, sort_dicts=False)
    return (
        PY_HEADER
        + '"""The spec of spec/ as data: the runtime catalogue is built from it."""\n\n'
        + "from typing import Any\n\n"
        + f"SPEC: dict[str, Any] = {literal}\n"
    )
