"""The flush air-data sensor: five FADS port pressures from the aircraft truth, and their air-data truth."""
