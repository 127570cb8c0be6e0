"""Kinematics: rotations, Euler angles, angular velocity, conversions, path-ordered exponentials (3.1, 3.5)."""
