"""Planar scenes on pymunk: spade and hammer in the x-z plane, scythe in the x-y plane."""
