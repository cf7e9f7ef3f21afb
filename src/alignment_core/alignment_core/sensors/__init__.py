"""Sensor models (simulation): slave IMU errors, master INS, LDV, Doppler radar, timing, presets."""


