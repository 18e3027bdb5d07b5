"""MJCF and YAML describing the synthetic world: box, table, camera, hand, grasps, users, masses.

Kept as a package so that the files install with the code; load them with
``importlib.resources.files("sim_assets")``.
"""
