"""The robot as a MAVLink vehicle (issue 6).

* ``app_port``: :class:`VehicleApp`, what the endpoint needs from the robot
  application, and the :class:`VehicleTelemetry` snapshot it reads;
* ``endpoint``: :class:`VehicleEndpoint`, the sans-I/O vehicle composing the
  ``shared.mavlink`` cores (commands, missions, parameters, FTP, signing);
* ``telemetry``, ``progress``, ``failsafe``, ``user_commands``: the pieces it
  streams, reports, times and answers with;
* ``ftp_memory``, ``robot_params``, ``param_file``: the robot-only sides of FTP and
  parameters (the memory and upload area it serves, its parameters bound to the
  config, the file they persist in);
* ``options``: its files and signing setup;
* ``udp_vehicle``: :class:`UdpVehicle`, the endpoint on a UDP socket;
  ``stream_vehicle``: :class:`StreamVehicle`, on a serial or TCP stream; ``vehicle_io``:
  what both share; ``vehicle_link``: the transport of an address, and the endpoint on it.
"""

from robot.vehicle.app_port import GcsLostAction, ServoTelemetry, VehicleApp, VehicleTelemetry
from robot.vehicle.endpoint import LinkStats, VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.stream_vehicle import StreamVehicle
from robot.vehicle.udp_vehicle import UdpVehicle

__all__ = [
    "GcsLostAction",
    "LinkStats",
    "ServoTelemetry",
    "SigningSetup",
    "StreamVehicle",
    "UdpVehicle",
    "VehicleApp",
    "VehicleEndpoint",
    "VehicleFiles",
    "VehicleTelemetry",
]
