"""Primary and secondary interfaces (ports 30001/30002/30011/30012)."""
