"""The ground station: MAVLink ground station core, mission dispatch, telemetry, ground log.

Modules: ``station`` (the link and the blocking API), ``fleet`` (vehicles by system
id), ``mission_watch`` (whether a goal was reached), ``telemetry_text`` (lines for
people), ``watch`` (live telemetry lines), ``teleop`` (keyboard driving, from a
terminal; the dead-man of a remote stick), ``ground_log`` (every packet in and out, MCAP
and tlog), and ``web`` (``vmnav ground web``: the station as a web app). The sans-I/O ends
of the MAVLink protocols the station drives are the GCS roles in ``shared.mavlink``
(its module docstring).
"""
