"""The one small error hierarchy of cosim.

Every message names the thing that is wrong, the value it had and what is allowed, so a user
can fix the input without reading our source.
"""

from __future__ import annotations

from collections.abc import Sequence


class CosimError(Exception):
    """Base class of every error cosim raises on purpose."""


class ConfigurationError(CosimError, ValueError):
    """A parameter, a scenario or a setup value is not acceptable.

    Raised with the full message text; prefer :meth:`out_of_range` for the common case.
    """

    @classmethod
    def out_of_range(
        cls, name: str, value: object, allowed: str, *, where: str = ""
    ) -> ConfigurationError:
        """Build the standard message: ``NAME = VALUE is outside ALLOWED``.

        Parameters
        ----------
        name : str
            Parameter name as the user wrote it (vendor name alongside where useful).
        value : object
            The offending value.
        allowed : str
            The allowed range or set, e.g. ``"0..65535"``.
        where : str, optional
            Location prefix such as ``"program.bas line 12"``.
        """
        prefix = f"{where}: " if where else ""
        return cls(f"{prefix}{name} = {value!r} is not allowed (allowed: {allowed})")


class FmuError(CosimError):
    """An FMU call failed; carries the FMU's own log messages.

    Parameters
    ----------
    message : str
        What we were doing when it failed.
    log : sequence of str
        The messages the FMU logged (most recent last).
    """

    def __init__(self, message: str, log: Sequence[str] = ()) -> None:
        self.log = tuple(log)
        text = message
        if self.log:
            text += "\nFMU log:\n  " + "\n  ".join(self.log[-20:])
        super().__init__(text)


class PlantTerminated(CosimError):
    """A plant FMU asked to end the simulation (FMI 2.0 Discard / fmi2Terminated, FMI 3.0 terminateSimulation).

    Not a failure: the run ends at that instant with verdict TERMINATED (see :mod:`cosim.runner`).

    Parameters
    ----------
    message : str
        What happened, naming the plant and the FMU file.
    plant : str
        The plant's (instance) name.
    fmu : str
        The FMU file's name.
    t : int
        The tick at which the plant ended the simulation [ticks].
    reason : str
        How the FMU asked (which call, at which FMU time).
    log : sequence of str
        The FMU's last log messages (most recent last).
    """

    def __init__(self, message: str, plant: str = "", fmu: str = "", t: int = 0, reason: str = "",
                 log: Sequence[str] = ()) -> None:
        # every field in args: SimPy re-raises a failed process's exception as type(exc)(*exc.args)
        super().__init__(message, plant, fmu, t, reason, tuple(log))
        self.message, self.plant, self.fmu, self.t, self.reason, self.log = message, plant, fmu, t, reason, tuple(log)

    def __str__(self) -> str:
        return self.message + ("\nFMU log:\n  " + "\n  ".join(self.log[-20:]) if self.log else "")


class TimingViolation(CosimError):
    """A controller rule was broken at run time in a way the model cannot continue from."""


class ScenarioError(CosimError):
    """A user's scenario script is wrong; the message carries its file and line."""
