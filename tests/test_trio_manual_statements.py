"""Statements written from the Motion Coordinator Technical Reference Manual: none is refused (issue 28).

Each line is a statement in the manual's syntax (commands, parameters with AXIS() and PROC(), functions,
program flow, I/O, declarations). Every one must parse and compile; whatever the model does not
simulate is accepted (and, when it runs, listed in the notes or stopped with a message naming it),
never a syntax error. The lines are compiled one by one with the few names they use declared first.
"""

from __future__ import annotations

import pytest

from cosim.controllers.trio.basic import BasicProgram

CONTEXT = 'x = 1\nn = 2\ny = 0\ns = "text"\nDIM arr(10)\nlbl:\nsub1:\n'

STATEMENTS = """
BASE(0)
BASE(0, 1)
BASE(2, 3)
UNITS = 50
UNITS AXIS(2) = 1000
SPEED = 100
SPEED AXIS(1) = 2.5
ACCEL = 1000
DECEL = 500
CREEP = 10
JOGSPEED = 40
FAST_JOG = 7
FWD_JOG = 5
REV_JOG = 6
FWD_IN = 3
REV_IN = 4
DATUM_IN = 2
FHOLD_IN = 8
FS_LIMIT = 1000
RS_LIMIT = -1000
REP_DIST = 360
REP_OPTION = 1
MERGE = ON
MERGE = OFF
SRAMP = 100
SERVO = ON
SERVO AXIS(3) = OFF
FE_LIMIT = 1000
FE_RANGE = 100
FE_LIMIT_MODE = 1
P_GAIN = 1.5
I_GAIN = 0.01
D_GAIN = 5
OV_GAIN = -1
VFF_GAIN = 10
AFF_GAIN = 0.5
DAC = 0
DAC_SCALE = 16
OUTLIMIT = 1
D_ZONE_MIN = 3
D_ZONE_MAX = 10
FASTDEC = 5000
FHSPEED = 10
CLOSE_WIN = 10
OPEN_WIN = 5
CLUTCH_RATE = 0
BACKLASH_DIST = 0.1
ERRORMASK = 268
AXIS_ENABLE = ON
VERIFY = ON
PP_STEP = 4
ENCODER_BITS = 25
ENCODER_CONTROL = 1
ATYPE = 1
INVERT_STEP = ON
OFFPOS = 10
WDOG = ON
WDOG = OFF
DEFPOS(0)
DEFPOS(0, 0)
DEFPOS(-1000, -3500)
MOVE(10)
MOVE(10, 20)
MOVE(-5) AXIS(2)
MOVEABS(100)
MOVEABS(100, 200)
MOVEABS(0) AXIS(1)
MOVECIRC(10, 0, 5, 0, 1)
MOVECIRC(0, 20, 0, 10, 0)
MOVEMODIFY(250)
FORWARD
FORWARD AXIS(1)
REVERSE
REVERSE AXIS(2)
CANCEL
CANCEL AXIS(1)
CANCEL(1)
RAPIDSTOP
DATUM(0)
DATUM(1)
DATUM(3)
DATUM(4) AXIS(2)
DATUM(5)
DATUM(6)
CONNECT(1, 0)
CONNECT(-0.5, 2) AXIS(1)
CAMBOX(0, 99, 1, 1000, 0)
CAMBOX(100, 199, 50, 2000, 1, 2, 500)
CAM(0, 99, 1, 1000)
MOVELINK(100, 200, 20, 20, 0)
MOVELINK(50, 100, 0, 0, 1, 1)
MOVELINK(50, 100, 0, 0, 1, 2, 30)
REGIST(1)
REGIST(3) AXIS(1)
TRIGGER
WAIT IDLE
WAIT IDLE AXIS(2)
WAIT LOADED
WAIT UNTIL IN(3) = ON
WAIT UNTIL DPOS > 100
WAIT UNTIL MPOS AXIS(0) >= 50 AND IDLE AXIS(1)
WAIT UNTIL TICKS < 0
WAIT UNTIL PROC_STATUS PROC(0) = 0
WA(100)
WA(0.5)
TICKS = 1000
x = TICKS
x = TICKS PROC(2)
x = PROC_STATUS PROC(3)
x = PROCNUMBER
x = ERROR_LINE
x = RUN_ERROR
x = PMOVE
INDEVICE = 5
OUTDEVICE = 0
x = DPOS
x = MPOS AXIS(1)
x = VP_SPEED
x = AXISSTATUS
x = AXIS_STATUS AXIS(1)
x = MARK
x = REG_POS
x = MTYPE
x = NTYPE
x = REMAIN
x = FE
x = OFFPOS
x = ENDMOVE
x = DEMAND_EDGES
x = MSPEED
x = LINKAX
x = SERVO_PERIOD
x = IDLE
x = LOADED AXIS(2)
OP(8, ON)
OP(9, OFF)
OP(8, 1)
OP(256)
x = IN(0)
x = IN(0, 7)
x = IN
x = READ_OP(8)
x = READ_OP(8, 15)
INVERT_IN(3, ON)
x = AIN(0)
x = KEY
FLAG(3, ON)
x = FLAG(3)
FLAGS(146)
SET_BIT(1, 10)
CLEAR_BIT(2, 10)
x = READ_BIT(1, 10)
CLEAR
VR(10) = 5
VR(n) = VR(n + 1) * 2
TABLE(0, 10, 20, 30)
TABLE(1000, 110, 115, 195, 220)
x = TABLE(3)
x = ABS(-3)
x = INT(2.7)
x = FRAC(2.7)
x = SGN(-4)
x = SQR(2)
x = SIN(PI / 2)
x = COS(0)
x = TAN(0.5)
x = ATAN(1)
x = ATAN2(1, 1)
x = ASIN(0.5)
x = ACOS(0.5)
x = EXP(1)
x = LN(10)
x = 2 ^ 8
x = 17 MOD 5
x = 10 AND 6
x = 10 OR 6
x = 10 XOR 6
x = NOT 0
x = (x + 1) * (n - 2) / 3
x = $FF + $10
x = 1.5E3
x = TRUE
x = FALSE
s = CHR(65)
s = HEX(255)
s = STR(12.5)
x = VAL("42")
x = LEN(s)
s = LEFT(s, 2)
s = RIGHT(s, 2)
s = MID(s, 2, 2)
s = UCASE(s)
s = LCASE(s)
x = INSTR(s, "x")
PRINT "Hello"
PRINT "x = "; x
PRINT x, n
PRINT x[8, 2]
PRINT x[3]
PRINT #5, "channel 5"
PRINT #1, x;
PRINT
PRINT ("text")
PRINT CHR(13);
PRINT HEX(x)
? MPOS
INPUT n
INPUT #1, n
INPUT "value", n
GET k
GET #5, k
LINPUT #5, VR(20)
DIM a AS INTEGER
DIM b AS FLOAT
DIM c AS BOOLEAN
DIM d AS STRING(20)
DIM e(100)
DIM f(3, 4) AS INTEGER
CONSTANT "max_speed", 500
GLOBAL "counter", 100
ON BASICERROR GOTO lbl
ON BASICERROR GOSUB sub1
ON n GOTO lbl, sub1
ON n GOSUB sub1, lbl
GOTO lbl
GOSUB sub1
RETURN
RUN "MAIN"
RUN "MAIN", 3
STOP "MAIN"
STOP "MAIN", 3
STOP
HALT
PROCESS
IF x > 1 THEN OP(8, ON)
IF x > 1 THEN OP(8, ON) ELSE OP(8, OFF)
SETCOM(19200, 8, 1, 0, 1, 4)
SCOPE(ON, 1, 0, 1000, MPOS AXIS(0), DPOS AXIS(0))
AUTORUN
EPROM
PSWITCH(0, ON, 0, 8, ON, 100, 200)
ENABLE_OP(65535)
SEND(0, 1, 2)
MHELICAL(10, 0, 5, 0, 1, 20)
ADDAX(1)
B_SPLINE(1, 0, 100, 200, 5)
x = INPUTS0
x = INPUTS1
x = AIN0
x = AIN3 AND $FFF
x = AINBI1
AOUT0 = 1000
AOUT3 = -2047
x = AOUT1
CHANNEL_READ(41, 100, 10)
TIMER(0, 8, 1, 100)
TIMER(1, 9, 0, 250, 1)
ENCODER_RATIO(8192, 7200)
ENCODER_RATIO(1, 2) AXIS(1)
STEP_RATIO(1, 2)
STEP_RATIO(4, 1) AXIS(2)
REGIST_SPEED = 1
REGIST_SPEED AXIS(1) = 250
x = REGIST_SPEED
OPEN #5 AS "log" FOR OUTPUT
OPEN #40 AS "data" FOR INPUT
CLOSE #5
CLOSE #40
x = KEY #1
WAIT UNTIL KEY #0
x = FLAGS
x = IEEE_IN(63, 128, 0, 0)
x = IEEE_OUT(1.5, 0)
x = TRANS_DPOS
x = TRANSITIONS
x = MARKB
x = REG_POSB AXIS(1)
x = FE_LATCH
x = S_REF_OUT
x = ADDAX_AXIS
x = ENCODER_STATUS
x = ENCODER_TYPE
x = ENCODER_ID
SSI_BITS = 25
MICROSTEP = ON
DRIVE_CONTROL = 3
AXIS_MODE = 0
DISPLAY = 1
FRAME = 0
POWER_UP = 1
x = POWER_UP
LIMIT_BUFFERED = 64
TIME = 0
DATE = 0
x = DAY
ADDRESS = 3
x = CHECKSUM
x = COMMSERROR
x = COMMSTYPE
STORE
EXECUTE "RUN"
INITIALISE
DIR
RECORD(0, 1)
MATCH(1, 2)
"""

BLOCKS = [
    "FOR i = 1 TO 10\n  x = x + i\nNEXT i",
    "FOR i = 10 TO 1 STEP -2\nNEXT",
    "REPEAT\n  x = x + 1\nUNTIL x > 10",
    "WHILE IN(4) = OFF\n  WA(10)\nWEND",
    "IF x = 1 THEN\n  y = 2\nELSEIF x = 2 THEN\n  y = 3\nELSE\n  y = 4\nENDIF",
    "label_one:\nGOTO label_one",
]


def statements() -> list[str]:
    return [line for line in STATEMENTS.strip().splitlines() if line.strip()]


def test_there_are_at_least_150_statements() -> None:
    assert len(statements()) + len(BLOCKS) >= 150


@pytest.mark.parametrize("statement", statements() + BLOCKS)
def test_a_statement_of_the_manual_is_never_refused(statement: str) -> None:
    program = BasicProgram.parse(f"{CONTEXT}{statement}\nVR(0) = x + n + y + LEN(s) + arr(0)\n", name="manual.bas")
    assert program.compiled.ops
