"""Universal Robots' RTDE and primary/secondary interfaces, from one declarative spec.

Start with `rtde_spec.codec` (RTDE packages), `rtde_spec.recipe_codec` (data
packages of a recipe), `rtde_spec.recipe_validation` (offline recipe checks),
`rtde_spec.primary.codec` (primary/secondary messages) and
`rtde_spec.catalogue` (the field catalogue). Errors derive from
`rtde_spec.errors.RtdeSpecError`.
"""

__version__ = "0.1.0"
