"""Kalman filters sharing one small interface: predict, update, x, P, diagnostics."""
