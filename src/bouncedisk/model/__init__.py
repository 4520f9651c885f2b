"""The model: what is simulated.

Parameters (and the physical conversion), scenes, stator kinematics, YAML as users write it, the
one-line user error, and a scene translated into the engine's configuration.
"""
