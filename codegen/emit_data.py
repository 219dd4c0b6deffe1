"""Emit _generated/spec_data.py: the validated spec as a Python literal.

The runtime rebuilds the meta-model from it, so the installed package needs no
YAML files and answers exactly what spec/ said at generation time.
"""

from __future__ import annotations

from rtde_spec.metamodel.schema import Spec

from .render import literal_module


def emit_spec_data(spec: Spec) -> str:
    return literal_module(
        "The spec of spec/ as data: the runtime catalogue is built from it.",
        "SPEC",
        spec.model_dump(mode="json", exclude_defaults=True),
    )
