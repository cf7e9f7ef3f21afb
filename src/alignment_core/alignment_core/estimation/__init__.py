"""Estimation: the transfer-alignment engine, its error models and filter algorithms. Never
imports the simulator (ship, aircraft, sensors): it runs unchanged on recorded data."""


