"""python -m rtde_spec: the rtde-spec command line."""

import sys

from rtde_spec.cli.main import main

sys.exit(main())
