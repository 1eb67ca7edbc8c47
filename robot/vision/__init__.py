"""The robot's vision front end: corners, ZNCC matching, relative pose, control law."""
