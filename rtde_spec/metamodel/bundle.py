"""Every spec file below one root, loaded once: the bundle codegen hands to each emitter.

No emitter opens a file of its own, so `python -m codegen --spec DIR` (and `spec import
--write`, which generates an edited copy in memory) regenerate from DIR alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rtde_spec.metamodel.arms import ArmsFile, load_arms
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.dashboard import DashboardFile, load_dashboard
from rtde_spec.metamodel.external import ExternalControlFile, load_external
from rtde_spec.metamodel.loader import default_spec_root, load_spec
from rtde_spec.metamodel.realtime import RealtimeFile, load_realtime
from rtde_spec.metamodel.schema import Primitive, Spec
from rtde_spec.metamodel.urscript import ScriptFunctions, load_urscript


@dataclass(frozen=True)
class SpecBundle:
    """The protocol spec (RTDE, primary) and the tables with meta-models of their own."""

    root: Path
    spec: Spec
    catalogue: Catalogue
    arms: ArmsFile
    dashboard: DashboardFile
    realtime: RealtimeFile
    external: ExternalControlFile
    urscript: ScriptFunctions

    @property
    def primitives(self) -> dict[str, Primitive]:
        return {p.name: p for p in self.spec.primitives.primitives}


def load_bundle(root: Path | str | None = None) -> SpecBundle:
    """Load, validate and check every spec file below `root` (default: the checkout's spec/)."""
    base = Path(root) if root is not None else default_spec_root()
    spec = load_spec(base)
    catalogue = Catalogue(spec)
    return SpecBundle(
        root=base,
        spec=spec,
        catalogue=catalogue,
        arms=load_arms(base),
        dashboard=load_dashboard(base),
        realtime=load_realtime(base, catalogue),
        external=load_external(base),
        urscript=load_urscript(base),
    )
