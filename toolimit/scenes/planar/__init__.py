"""Planar scenes on pymunk: spade and hammer in the x-z plane, scythe in the x-y plane.

Modules: ``spade``, ``hammer``, ``scythe`` (the scenes, reached through the registry),
``kinematic_tool`` (the 3D tool pose projected into the plane and driven as kinematic bodies),
``sand_pile`` (the spade world's sand, walls and ground) and ``scoop`` (a hand-made scoop that
solves the spade world, the LfD baseline's demonstration).
"""
