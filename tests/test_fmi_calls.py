"""The FMI call-state table of our FMUs: a call the standard does not allow in the instance's state is
refused with fmi2Error / fmi3Error and a log message naming the function and the state.

    FMI 3.0:  instantiated --enterInitializationMode--> initialization --exit--> step --terminate--> terminated
              doStep allowed only in step mode; after an error only getters, state and FreeInstance
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from cosim.fmu import Fmu
from cosim.fmubuild import ensure_fmu

pytestmark = pytest.mark.fmu


@pytest.fixture
def laser3() -> Iterator[tuple[FMU3Slave, list[str]]]:
    path = ensure_fmu("Laser", 3)
    unzip = tempfile.mkdtemp()
    extract(str(path), unzipdir=unzip)
    md = read_model_description(str(path))
    log: list[str] = []
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="laser")
    fmu.instantiate(logMessage=lambda env, status, category, message: log.append(message.decode()))
    yield fmu, log
    fmu.freeInstance()
    shutil.rmtree(unzip, ignore_errors=True)


def test_fmi3_do_step_before_initialisation_is_refused_and_logged(laser3: tuple[FMU3Slave, list[str]]) -> None:
    fmu, log = laser3
    with pytest.raises(FMICallException) as info:
        fmu.doStep(0.0, 1e-3)
    assert info.value.status == 3  # fmi3Error
    assert log[-1] == "fmi3DoStep must not be called in instantiated"


def test_fmi3_after_an_error_only_getters_and_teardown_are_allowed(laser3: tuple[FMU3Slave, list[str]]) -> None:
    fmu, log = laser3
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    with pytest.raises(FMICallException):
        fmu.exitInitializationMode()  # not in step mode: an error, the instance is now in its error state
    assert log[-1] == "fmi3ExitInitializationMode must not be called in step mode"
    vr = read_model_description(str(ensure_fmu("Laser", 3))).modelVariables[0].valueReference
    fmu.getFloat64([vr])  # getters stay allowed for debugging
    with pytest.raises(FMICallException):
        fmu.doStep(1e-3, 1e-3)
    assert "fmi3DoStep must not be called in" in log[-1]


def test_fmi2_set_up_after_initialisation_is_refused_and_logged() -> None:
    with Fmu(ensure_fmu("Laser", 2), instance_name="laser") as fmu:  # initialised: step mode
        with pytest.raises(FMICallException) as info:
            fmu._fmu.setupExperiment(startTime=0.0)  # the raw FMI call, as another importer might make it
        assert info.value.status == 3  # fmi2Error
        assert fmu.log[-1].endswith("fmi2SetupExperiment must not be called in step mode")
        with pytest.raises(FMICallException):
            fmu._fmu.doStep(0.0, 1e-3)  # the instance is in its error state now
