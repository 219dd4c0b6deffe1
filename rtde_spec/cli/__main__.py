import sys

from rtde_spec.cli.main import main

sys.exit(main())
