"""The ground station: MAVLink ground station core, mission dispatch, telemetry, ground log."""
