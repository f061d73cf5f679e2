"""I-variable setup text: hex and decimal, comments, clear errors with file and line."""

from __future__ import annotations

from fractions import Fraction

import pytest

from cosim.controllers.pmac.ect import RUNNING, TriggeredTimeBaseEntry
from cosim.controllers.pmac.ivartable import split
from cosim.controllers.pmac.machine import Pmac
from cosim.controllers.pmac.setupfile import Assignment, parse_setup
from cosim.errors import ConfigurationError
from cosim.kernel import Simulation
from cosim.plants.analytic import IdealConveyor

MANUAL_EXAMPLE = """\
; Turbo PMAC triggered time base, as in the manual
I10=3713707                ; servo interrupt time (default)
I8008=$AF8018 I8009=64     ; running, PMAC2-style IC 0 channel 4; SF for 256 counts/ms
i5193 = @I8009             ; CS1 time base from the entry's result
I5194=8388607
"""


def test_parse_hex_decimal_address_of_and_comments() -> None:
    assignments = parse_setup(MANUAL_EXAMPLE, source="cell.pmc")
    assert assignments == (
        Assignment(10, 3_713_707, 2, "cell.pmc", 1),
        Assignment(8008, 0xAF8018, 3, "cell.pmc", 1),
        Assignment(8009, 64, 3, "cell.pmc", 15),
        Assignment(5193, 0x350A, 4, "cell.pmc", 1),
        Assignment(5194, 8_388_607, 5, "cell.pmc", 1),
    )
    assert assignments[3].where == "cell.pmc:4:1"


def test_cs_numbering_pmac_and_turbo() -> None:
    """Turbo numbering Isx (I5100..I6699, 16 systems); the non-Turbo Ix93/Ix94 of CS 1..8 stay aliases.

    The Turbo PMAC has no motor variables Ixx93 and Ixx94, so I193..I894 mean nothing else; I195 is
    motor 1's Ixx95 (power-on servo position format) on the Turbo PMAC.
    """
    assert split(193) == ("CS", 1, 93) and split(894) == ("CS", 8, 94)
    assert split(5193) == ("CS", 1, 93) and split(5894) == ("CS", 8, 94) and split(6694) == ("CS", 16, 94)
    assert split(93) == ("GLOBAL", 0, 93) and split(995) == ("MOTOR", 9, 95) and split(196) == ("MOTOR", 1, 96)
    assert split(195) == ("MOTOR", 1, 95) and split(5887) == ("CS", 8, 87) and split(7013) == ("SERVO_IC", 0, 13)


VALUE = r"is not a value \(write a number: decimal, \$hex or @In; a variable; or an expression of them\)$"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("I10=3713707\nI130=8388608",
         r"^cell.pmc:2:1: I130 \(Ixx30, PID proportional gain\) = 8388608 is not allowed \(allowed: integers "
         r"-8388608..8388607\)$"),
        ("I7000=$1000000", r"^cell.pmc:1:1: I7000 \(I7m00, Servo IC 0 multi-channel I-variable\) = 16777216 is not "
                           r"allowed"),
        ("I194=8388608", r"^cell.pmc:1:1: I194 \(Ix94, time-base slew limit\) = 8388608 is not allowed "
                         r"\(allowed: integers 0..8388607"),
        ("\n\nI5194=-1", r"^cell.pmc:3:1: I5194 \(Ix94, time-base slew limit\) = -1 is not allowed"),
        ("I10=0", r"^cell.pmc:1:1: I10 \(servo interrupt time\) = 0 is not allowed \(allowed: integers 1..8388607"),
        ("I8011=2184.5",
         r"^cell.pmc:1:1: I8011 \(conversion table line\) = 2184.5 is not allowed \(allowed: integers"),
        ("I8011=$1000000",
         r"^cell.pmc:1:1: I8011 \(conversion table line\) = 16777216 is not allowed \(allowed: integers 0..16777215"),
        ("I10=fast", rf"^cell.pmc:1:5: 'fast' {VALUE}"),
        # non-finite and absurdly large values are refused at once (issue 22: a crash, or a hang for 1e99999999)
        ("I10=Infinity", rf"^cell.pmc:1:5: 'Infinity' {VALUE}"),
        ("I10=sNaN", rf"^cell.pmc:1:5: 'sNaN' {VALUE}"),
        ("I10=1e99999999",
         r"^cell.pmc:1:6: syntax error: unexpected 'e99999999' \(PMAC numbers are written without an exponent\)$"),
        ("I10=" + "9" * 5000, r"^cell.pmc:1:5: number = 9999999999999999999999999999999999999... is not allowed "
                              r"\(allowed: at most 15 integer and 30 fraction digits"),
        ("I194=100000000000000", r"^cell.pmc:1:1: I194 \(Ix94, time-base slew limit\) = 100000000000000 is not "
                                 r"allowed \(allowed: integers 0..8388607 \(2\^-23 ms per servo cycle\)\)$"),
        ("I193=@I10", r"^cell.pmc:1:6: @I10 = address of I10 is not allowed \(allowed: @I8000..@I8191"),
        ("&1", r"^cell.pmc:1:1: '&1' is not an I-variable assignment"),
        ("I10=3713707 #1->X", r"^cell.pmc:1:13: '#1->X' is not an I-variable assignment"),
        ("I10=P1", r"^cell.pmc:1:1: 'I10=P1' is not an I-variable assignment"),
    ],
)
def test_setup_errors_name_line_variable_value_and_range(text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        parse_setup(text, source="cell.pmc")


def test_close_and_comments_alone_are_an_empty_setup() -> None:
    """Setup files often start with CLOSE (no buffer open): nothing to apply."""
    assert parse_setup("CLOSE ; make sure no buffer is open\n; only a comment\n\n") == ()


def test_manual_example_loads_into_the_machine(sim: Simulation) -> None:
    belt = IdealConveyor(sim, speed_counts_per_ms=256)
    pmac = Pmac(sim)
    pmac.add_channel(0x078018, belt)
    pmac.load_setup(MANUAL_EXAMPLE, source="cell.pmc")
    entry = pmac.table.entry_at(0x3509)
    assert isinstance(entry, TriggeredTimeBaseEntry)
    assert (entry.method, entry.channel_address, entry.scale_factor) == (RUNNING, 0x78018, 64)
    assert pmac.get_ivar(8008) == 0xAF8018 and pmac.get_ivar(8009) == 64
    assert pmac.get_ivar(5193) == pmac.get_ivar(193) == 0x350A
    assert pmac.coordinate_system(1).ix94 == 8_388_607
    pmac.start()
    sim.run(until=pmac.clock.t(5) + 1)
    assert abs(pmac.coordinate_system(1).percent - 100) <= Fraction(100 * 2 * 64, 3_713_707)  # one 1/256 count


def test_setup_with_an_untriggered_entry_and_pmac_style_numbers(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.add_channel(0x078000, IdealConveyor(sim, speed_counts_per_ms=48))
    pmac.load_setup("I8000=$078000\nI8001=$403501\nI8002=2048\nI193=$3503 I194=8388607\n")
    pmac.start()
    sim.run(until=pmac.clock.t(4) + 1)
    assert pmac.coordinate_system(1).source_value in (2_781_184, 2_785_280)  # 75 % within one 1/32 count


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("I8010=$978008", r"I8010 = \$978008 starts a two-line time-base entry, but its SCALE_FACTOR line I8011"),
        ("I8010=$978008\nI8011=0", r"setup:2:1: SCALE_FACTOR \(I8011\) = 0 is not allowed \(allowed: integers "
                                   r"1..8388607\)"),
        ("I8010=$C78008\nI8011=64", r"setup:1:1: I8010 \(method digit \$C\) = \$C78008 is not allowed "
                                    r"\(allowed: method digits \$0 \(1/T\), \$4 \(time base\), \$9"),
        ("I8010=$978008\nI8011=64\nI193=1833",
         r"setup:3:1: I193 \(Ix93 of CS1\) = \$0729 \(1833\) is not allowed "
         r"\(allowed: addresses of time-base registers: \$2000 \(CS1 % register\), "
         r"\$350C \(TriggeredTimeBaseEntry result\)\)"),
    ],
)
def test_setup_errors_in_the_table_and_ix93(sim: Simulation, text: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        Pmac(sim).load_setup(text)


def test_run_time_writes_check_the_method_digit(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.add_channel(0x078008, IdealConveyor(sim, speed_counts_per_ms=64))
    pmac.load_setup("I8010=$978008 I8011=256 I5193=@I8011")
    pmac.start()
    with pytest.raises(ConfigurationError, match=r"line 7: I8010 \(method digit \$8\) = \$878008 is not allowed "
                                                 r"\(allowed: \$9 \(frozen\), \$A \(running\), \$B \(armed\)\)"):
        pmac.set_ivar(8010, 0x878008, where="plc.pmc line 7")
    with pytest.raises(ConfigurationError, match=r"I8010 \(source address\) = \$978010"):
        pmac.set_ivar(8010, 0x978010)
    pmac.set_ivar(8011, 128)  # SCALE_FACTOR may change while running
    with pytest.raises(ConfigurationError, match=r"SCALE_FACTOR \(I8011\) = 0"):
        pmac.set_ivar(8011, 0)
    with pytest.raises(ConfigurationError, match="I10 cannot change while the servo clock runs"):
        pmac.set_ivar(10, 2**21)
    with pytest.raises(ConfigurationError, match=r"I8020 = \$000001: writing a conversion-table line that holds no"):
        pmac.set_ivar(8020, 1)


def test_read_x_of_unknown_address(sim: Simulation) -> None:
    pmac = Pmac(sim)
    with pytest.raises(ConfigurationError, match=r"X-memory address = \$07800B \(491531\) is not allowed"):
        pmac.read_x(0x07800B)


def test_unbound_channel_is_named_at_start(sim: Simulation) -> None:
    pmac = Pmac(sim)
    pmac.load_setup("I8010=$978008 I8011=256")
    with pytest.raises(ConfigurationError, match=r"channel address of the TriggeredTimeBaseEntry at \$350B \(I8010\) = "
                                                 r"\$78008 \(491528\) is not allowed \(allowed: addresses of encoder "
                                                 r"channels: none added\)"):
        pmac.start()
