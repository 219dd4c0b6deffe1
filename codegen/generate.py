"""Run every emitter over one spec: relative output path -> file text."""

from __future__ import annotations

from rtde_spec.spec.catalogue import Catalogue
from rtde_spec.spec.schema import Spec

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
from .render import PY_HEADER

GEN = "rtde_spec/_generated"


def generate(spec: Spec) -> dict[str, str]:
    catalogue = Catalogue(spec)
    prims = {p.name: p for p in spec.primitives.primitives}
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
        f"{GEN}/rtde_spec.lua": emit_lua(spec, catalogue) + emit_lua_drivers(prims, catalogue),
        "docs/reference/README.md": emit_index_doc(spec, catalogue),
        "docs/reference/rtde-fields.md": emit_fields_doc(spec, catalogue),
        "docs/reference/rtde-packages.md": emit_packages_doc(spec),
        "docs/reference/enums.md": emit_enums_doc(spec),
        "docs/reference/primary.md": emit_primary_doc(spec),
        "docs/reference/rtde-types.md": emit_types_doc(spec, catalogue),
        **emit_arms(),
        **emit_dashboard(),
        **emit_realtime(catalogue),
        **emit_external(prims),
        **emit_urscript(),
    }
