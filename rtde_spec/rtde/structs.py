"""The construct structs of RTDE, public API: generated from spec/ by codegen.

Import from here, not from `rtde_spec._generated` (the generator's output, whose
layout may change).
"""

from rtde_spec._generated.rtde_structs import *  # noqa: F403
