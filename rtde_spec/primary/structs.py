"""The construct structs of the primary and secondary interfaces: public API, generated from spec/.

Import from here, not from `rtde_spec._generated` (the generator's output, whose
layout may change).
"""

from rtde_spec._generated.primary_structs import *  # noqa: F403
