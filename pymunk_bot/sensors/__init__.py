"""Sensors: each reads the world after every body has moved, at its own rate."""
