"""The simulator: pymunk world, 3D landmark field, Pioneer 3-AT body, people, fisheye renderer.

Imports only shared/. It replaces the robot's motors and camera, in lock-step
(one process) or, in later issues, behind real transports.
"""
