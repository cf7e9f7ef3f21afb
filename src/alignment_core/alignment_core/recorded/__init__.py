"""Recorded logs in: a user's IMU / master INS / LDV / Doppler tables (CSV or MATLAB .mat)
converted to the records the filter takes (samples.py), with the units, axes, attitude
conventions and time bases of the log stated in a layout (the canonical one by default).

Pure numpy/scipy: the ROS importer (alignment_ros.importer) writes the result to a bag.
"""
