"""The states of an exploration grid's cells (exploration.FloorGrid), shared by the modules that read it."""
UNKNOWN, FREE, OCCUPIED = 0, 1, 2
