"""Laser Doppler velocimeter: aircraft velocity relative to the deck."""
