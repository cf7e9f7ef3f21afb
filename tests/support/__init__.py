"""Helpers shared by several test modules (not tests themselves): importable as `support.*`
because pytest.ini declares `pythonpath = tests`."""
