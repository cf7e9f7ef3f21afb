"""The air-data estimator: FADS ports and an INS in, air velocity, pressures and wind out (no truth)."""
