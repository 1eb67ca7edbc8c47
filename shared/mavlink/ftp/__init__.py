"""MAVLink FTP (FILE_TRANSFER_PROTOCOL, id 110): files on the vehicle, read and written by a GCS.

References: mavlink-vehicle.md §0.5-0.8 and §1.6, mavlink.io/en/services/ftp.html,
pymavlink ``mavftp.py``.

* ``payload``: the 251-byte payload both ends speak (opcodes, NAK codes, the
  directory entry, MAVLink's CRC32);
* ``vehicle``: :class:`~shared.mavlink.ftp.vehicle.FtpServer`, the vehicle's end,
  over an :class:`~shared.mavlink.ftp.vehicle.FtpFileSystem` (sessions, bursts, the
  retry cache);
* ``gcs``: :class:`~shared.mavlink.ftp.gcs.FtpClient`, the ground station's end
  (list, get, put, CRC, with retries).

What the robot serves (its memory, read-only, and an upload area) is robot-only:
``robot/vehicle/ftp_memory.py``.
"""
