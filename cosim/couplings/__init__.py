"""Couplings: the one place where a controller's signals meet a plant's variables.

Controllers know signals (and offer them bundled as *ports*, :mod:`cosim.signals`); plants know
variables (:class:`cosim.master.PlantLike`); a coupling joins the two and names the plant
variables it uses in one place, as *roles* with the bundled FMU's names as defaults. A user's
FMU with other names is coupled by mapping its variables onto the roles
(:mod:`~cosim.couplings.roles`).

================================  ===========================================  ========================
module                            joins                                        plant roles (defaults)
================================  ===========================================  ========================
:mod:`~.stepper`                  step/direction port -> stepper               step_rate, step_phase,
                                                                               commanded_steps
:mod:`~.laser`                    PWM port (gate, mark, WDOG) -> laser         enable, gate, pwm_period,
                                                                               pwm_on, pwm_phase
:mod:`~.switches`                 plant switch outputs -> switch port          limit_pos, limit_neg, home
:mod:`~.encoder`                  plant encoder/mark -> encoder input, trigger encoder_count, edge_direction,
                                                                               t_last_edge, t_prev_edge, mark
:mod:`~.servo`                    motor DAC -> command, encoder -> feedback    u_cmd + the encoder roles
:mod:`~.ideal_axis`               step pulses -> switch (no plant model)       (none)
================================  ===========================================  ========================

Example::

    engine = PulseEngine(sim)
    x = run.plant("Stepper", name="stepper_x", preset="nema17_17hs16_2004s1")
    couple_stepper(engine.step_dir(0), x)
    couple_switches(x, engine.switch_port(0))
    mine = run.plant("motor.fmu", name="mine")        # a user's FMU with other names
    couple_stepper(engine.step_dir(1), mine, variables={"step_rate": "f_step", "step_phase": "phi0",
                                                        "commanded_steps": None})
"""

from cosim.couplings.laser import couple_laser
from cosim.couplings.roles import resolve
from cosim.couplings.stepper import StepperCoupling, couple_stepper
from cosim.couplings.switches import couple_switches

__all__ = ["StepperCoupling", "couple_laser", "couple_stepper", "couple_switches", "resolve"]
