"""URCL's external-control protocols (reverse, script sender, trajectory, script command), from the spec."""
