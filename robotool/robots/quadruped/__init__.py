"""The quadruped: a Unitree Go1-sized legged robot."""
