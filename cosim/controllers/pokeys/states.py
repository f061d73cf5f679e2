"""Engine and axis state codes, as the device reports them in its status.

These are the values of the ``pokeys.state`` and ``pokeys.<axis>.axis_state`` signals.
"""

from __future__ import annotations

from enum import IntEnum


class EngineState(IntEnum):
    """Pulse engine state (status byte 'engine state', signal ``pokeys.state``)."""

    STOPPED = 0  # no pulses
    INTERNAL = 1  # internal position or speed control (slots produced into the buffer)
    BUFFER = 2  # slots fed from the slot buffer by the host
    JOGGING = 10  # set_speed control, limit switches ignored
    STOPPING = 11  # reserved by the device; not entered by the model
    HOME = 20  # homing finished
    HOMING = 21  # homing in progress
    STOP_LIMIT = 100  # error: stopped by a limit switch
    STOP_EMERGENCY = 101  # error: stopped by the emergency input

    @property
    def is_error(self) -> bool:
        """True for the error/stop states entered by a switch."""
        return self >= EngineState.STOP_LIMIT


class AxisState(IntEnum):
    """Per-axis state (status bytes 'axis states', signal ``pokeys.<axis>.axis_state``)."""

    STOPPED = 0
    READY = 1
    RUNNING = 2
    HOME = 10  # homed: counter reset at the home switch
    HOMING_START = 11
    HOMING_SEARCH = 12  # moving towards the home switch at the homing speed
    HOMING_BACK = 13  # backing off the switch at the return speed
    ERROR = 20
    LIMIT = 30  # this axis' limit switch stopped the engine
