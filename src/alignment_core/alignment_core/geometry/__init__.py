"""Geometry: the Earth (WGS-84, gravity, rates) and one set of rotation maths."""


