"""Run every emitter over one loaded spec bundle: relative output path -> file text.

Emitters get their part of the bundle and never open files, so what is generated is
exactly what the bundle (one spec root, or an edited copy in memory) says.
"""

from __future__ import annotations

from collections.abc import Callable

from rtde_spec.metamodel.bundle import SpecBundle

from .emit_arms import emit_arms
from .emit_constants import emit_catalogue_data, emit_constants
from .emit_dashboard import emit_dashboard
from .emit_data import emit_spec_data
from .emit_docs import (
    emit_enums_doc,
    emit_fields_doc,
    emit_index_doc,
    emit_packages_doc,
    emit_types_doc,
)
from .emit_enums import emit_enums
from .emit_external import emit_external
from .emit_lua import emit_lua
from .emit_lua_drivers import emit_lua_drivers
from .emit_primary import emit_primary_models, emit_primary_structs
from .emit_primary_docs import emit_primary_doc
from .emit_realtime import emit_realtime
from .emit_rtde import emit_rtde_models, emit_rtde_structs
from .emit_types import emit_types
from .emit_urscript import emit_urscript
from .render import GEN, PY_HEADER


def _protocol(b: SpecBundle) -> dict[str, str]:
    spec, catalogue = b.spec, b.catalogue
    return {
        f"{GEN}/__init__.py": PY_HEADER + '"""Code generated from spec/; import through rtde_spec."""\n',
        f"{GEN}/constants.py": emit_constants(spec),
        f"{GEN}/catalogue_data.py": emit_catalogue_data(catalogue),
        f"{GEN}/spec_data.py": emit_spec_data(spec),
        f"{GEN}/enums.py": emit_enums(spec),
        f"{GEN}/rtde_types.py": emit_types(catalogue),
        f"{GEN}/rtde_structs.py": emit_rtde_structs(spec),
        f"{GEN}/rtde_models.py": emit_rtde_models(spec),
        f"{GEN}/primary_models.py": emit_primary_models(spec),
        f"{GEN}/primary_structs.py": emit_primary_structs(spec),
        f"{GEN}/rtde_spec.lua": emit_lua(spec, catalogue) + emit_lua_drivers(b),
        "docs/reference/README.md": emit_index_doc(spec, catalogue),
        "docs/reference/rtde-fields.md": emit_fields_doc(spec, catalogue),
        "docs/reference/rtde-packages.md": emit_packages_doc(spec),
        "docs/reference/enums.md": emit_enums_doc(spec),
        "docs/reference/primary.md": emit_primary_doc(spec),
        "docs/reference/rtde-types.md": emit_types_doc(spec, catalogue),
    }


#: one entry per emitter family: bundle -> {relative path: text}; a new emitter is one line here
EMITTERS: tuple[Callable[[SpecBundle], dict[str, str]], ...] = (
    _protocol,
    lambda b: emit_arms(b.arms),
    lambda b: emit_dashboard(b.dashboard),
    lambda b: emit_realtime(b.realtime, b.catalogue),
    lambda b: emit_external(b.external, b.primitives),
    lambda b: emit_urscript(b.urscript),
)


def generate(bundle: SpecBundle) -> dict[str, str]:
    """Every generated file of `bundle`, by path relative to the repository root."""
    files: dict[str, str] = {}
    for emit in EMITTERS:
        files.update(emit(bundle))
    return files
