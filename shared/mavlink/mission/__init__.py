"""The mission protocol (devguide mission.md): upload, download and clear of the vehicle's mission.

* ``items``: :class:`~shared.mavlink.mission.items.MissionItem`, a mission item as
  the protocol carries it, whatever it means, and the refusal of a mission;
* ``goal``: what our items mean, "drive to key image N" (both ends encode and
  decode it);
* ``vehicle``: :class:`~shared.mavlink.mission.vehicle.MissionServer`, the
  vehicle's end (stores one mission, drives uploads, reports progress);
* ``gcs``: :class:`~shared.mavlink.mission.gcs.MissionClient`, the ground
  station's end (one operation at a time, with retries).
"""
