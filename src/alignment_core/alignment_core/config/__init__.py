"""Scenario assembly: loading, overrides and validation of a complete run."""


