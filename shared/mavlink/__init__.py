"""MAVLink between the robot (a vehicle) and the ground station, sans-I/O.

The robot is one MAVLink 2 system whose autopilot component (id 1) reports
itself as a generic-autopilot ground rover; the ground station talks to it with
the standard microservices (team reference ``reference/mavlink-vehicle.md``,
cited by section). Every protocol core here takes decoded pymavlink messages (or
FTP payloads) and ``now_ns`` and returns what to send, typed events and a timer
deadline; none touches a socket, a file or a clock. The robot's endpoint
(``robot/vehicle/``) and the ground station (``ground/station.py``) are the
adapters: they pack and parse bytes with :func:`~shared.mavlink.dialect.make_codec`
and carry them over :class:`~shared.udp_link.UdpLink`.

Where a protocol's two ends live
--------------------------------

One rule for every protocol: its pure core, **both roles** (``VEHICLE`` and
``GCS``), is here under **one name**. A protocol with a state machine on each end
is a package ``<protocol>/`` with ``vehicle.py`` (the vehicle's end), ``gcs.py``
(the ground station's end) and the wire parts both ends use; a protocol whose
ends share only stateless encoding is one module. What the robot alone does with
a protocol, with files or its config (what it serves, its parameters), lives in
``robot/vehicle/``; what the station does with it, in ``ground/``.

==============  ======================================  ==================================
protocol        both ends, in shared/mavlink/           its users outside shared/mavlink/
==============  ======================================  ==================================
heartbeat,      ``modes`` (the HEARTBEAT, our mode      link loss:
modes           numbers, mode requests in either        ``robot/vehicle/failsafe.py``,
                encoding)                               ``ground/fleet.py``
commands        ``commands/``: ``vehicle``              ``robot/vehicle/user_commands.py``
                (dispatcher, the robot's table),        (the robot's answers to ours)
                ``gcs`` (client), ``intervals``
                (SET_MESSAGE_INTERVAL), ``user`` (our
                user-range commands)
mission         ``mission/``: ``items``, ``goal`` (our  ``robot/vehicle/progress.py``
                goal items), ``vehicle`` (server),      (reports the robot's progress)
                ``gcs`` (client)
parameters      ``params/``: ``table`` (declared        ``robot/vehicle/robot_params.py``
                parameters, wire encoding),             (bound to the config),
                ``vehicle`` (server), ``gcs`` (client)  ``robot/vehicle/param_file.py``
FTP             ``ftp/``: ``payload`` (codec, CRC32),   ``robot/vehicle/ftp_memory.py``
                ``vehicle`` (server, the file-system    (the memory and upload area)
                Protocol), ``gcs`` (client)
statustext      ``statustext`` (chunking, text length)  --
camera          ``camera`` (the camera component's     ``robot/vehicle/endpoint.py`` (its
                HEARTBEAT and answers; the stream as    camera component), ``ground/``
                a station reads it)                     (finds the stream)
signing         ``signing`` (keys, unsigned policy,     ``shared/key_file.py`` (reads and
                the signature check, the timestamp      creates the key file, for both
                bump, the timestamps kept across        entry points),
                restarts)                               ``shared/signing_timestamp_file.py``
telemetry       -- (single messages, no conversation)   ``robot/vehicle/telemetry.py``
                                                        builds them, ``ground/`` reads
==============  ======================================  ==================================

Common to all: ``vmnav.xml`` / ``vmnav_dialect.py``, the dialect (common.xml +
VISUAL_SERVO_STATUS) and its generated module; ``dialect``, the module with
MAVLINK20 set and a file-less codec; ``address``, (system, component) addresses
and target filtering. ``generate`` regenerates the dialect module from the XML
beside it: a developer's command, the one module here that touches files, which
nothing imports at run time.
"""
