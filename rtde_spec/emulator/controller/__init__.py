"""The controller: modes, faults, scenarios, registers and the running program, one model."""
