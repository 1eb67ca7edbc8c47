"""The command protocol (devguide command.md): COMMAND_LONG / COMMAND_INT, answered by COMMAND_ACK.

* ``vehicle``: :class:`~shared.mavlink.commands.vehicle.CommandDispatcher`, the
  vehicle's end (every command gets an ACK, a resent one is answered from a cache),
  and the robot's table of standard commands;
* ``gcs``: :class:`~shared.mavlink.commands.gcs.CommandClient`, the ground
  station's end (one command at a time, resent until ACKed);
* ``intervals``: the per-message stream intervals SET_MESSAGE_INTERVAL sets on the
  vehicle;
* ``user``: our own commands in common.xml's user range (numbers and the path-name
  encoding), which both ends speak.
"""
