"""RGB-D circle (hole) detection and the choice of the hole to shoot, for the C3 water UAVs."""
