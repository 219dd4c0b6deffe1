"""python -m rtde_spec: the rtde-spec command line."""

from rtde_spec.cli.main import entry

entry()
