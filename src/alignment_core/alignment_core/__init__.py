"""Pure-Python physics and estimation library for shipboard transfer alignment (no ROS imports)."""


