"""Shared rclpy glue: topics, QoS, message conversions, sim clock, parameters; recorder, player and echo."""
