"""Child processes keep byte code, as an installed package does.

pip compiles a package's modules when it installs them. With PYTHONDONTWRITEBYTECODE, set in
some sandboxes and CI, every child would compile the modules it imports from source instead
(~80 ms of CPU for a capture, the 200 kB generated data modules among them): a cost no
installed user pays, timed as if it were start-up. The byte code goes to a folder of the
run's own, not into the checkout.
"""

from __future__ import annotations

import os
from pathlib import Path


def keep_bytecode(folder: Path) -> dict[str, str]:
    """This process's environment, for its children: byte code kept under `folder`."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = str(folder / "pycache")
    return dict(os.environ)
