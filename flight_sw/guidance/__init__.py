"""Attitude guidance: the reference attitude, rate and angular acceleration over time."""
