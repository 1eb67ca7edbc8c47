"""MAVLink between the robot (a vehicle) and the ground station, sans-I/O.

The robot is one MAVLink 2 system whose autopilot component (id 1) reports
itself as a generic-autopilot ground rover; the ground station talks to it with
the standard microservices (team reference ``reference/mavlink-vehicle.md``,
cited by section). Every protocol core here takes decoded pymavlink messages and
``now_ns`` and returns messages to send, typed events and a timer deadline; none
touches a socket or a clock. The robot's endpoint and the ground link (adapters)
pack and parse bytes with :func:`~shared.mavlink.dialect.make_codec`.

Modules:

* ``vmnav.xml`` / ``vmnav_dialect.py``: the dialect (common.xml + VISUAL_SERVO_STATUS)
  and its generated module; ``generate``: regenerates it; ``dialect``: the module
  with MAVLINK20 set and a file-less codec.
* ``address``: (system, component) addresses and target filtering.
* ``modes``: our ArduRover-numbered modes, decoding mode requests (ArduPilot and
  PX4 encodings), the HEARTBEAT.
* ``mission_items``, ``goal``: mission items and the goal-item encoding;
  ``mission``: the vehicle's mission server; ``mission_client``: the ground's.
* ``param_table``, ``param_file``, ``params``: declared parameters, their JSON
  file, and both ends of the parameter protocol; ``robot_params``: the robot's
  parameters bound to its config.
* ``commands``: the command dispatcher and the robot's command table;
  ``intervals``: message stream intervals; ``statustext``: STATUSTEXT chunks.
* ``ftp``, ``ftp_memory``: MAVLink FTP and the files the robot serves; ``signing``:
  MAVLink 2 message signing.
"""
