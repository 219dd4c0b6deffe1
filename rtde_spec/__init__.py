"""Universal Robots' RTDE and primary/secondary interfaces, from one declarative spec.

Start with `rtde_spec.rtde.codec` (RTDE packages), `rtde_spec.recipes.codec` (data
packages of a recipe), `rtde_spec.recipes.validation` (offline recipe checks),
`rtde_spec.primary.codec` (primary/secondary messages) and
`rtde_spec.spec.catalogue` (the field catalogue). Errors derive from
`rtde_spec.errors.RtdeSpecError`.
"""

__version__ = "0.1.0"
