"""python -m rtde_spec: the rtde-spec command line."""

import sys

from .cli.main import main

sys.exit(main())
