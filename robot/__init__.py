"""Code that runs on the robot computer: ARIA driver, camera sources, vision, route follower."""
