' engrave.bas - a rounded label outline on a laser engraver (Trio EURO205X with the PWM FPGA, TN20-81)
'
' The outline is a 50 x 20 mm rectangle with 5 mm round corners. The long edges are engraved as
' 2 mm dashes: their positions go from TABLE into the gating FIFO of axis 3, which switches the
' laser at the exact step of each position (GT going +X, LT going -X). The corners and the short
' edges are engraved solid. The laser power follows the path speed (PWM_CONTROL(2)), so a corner,
' where the axes slow down, gets no more energy per mm than a straight.
'
' Axes: X = axis 3 (stepper, PWM output to the laser), Y = axis 2 (stepper); GT2 belts on 20-tooth
' pulleys and 1/16 microstepping: 80 steps/mm. Process 1 (this program) moves; process 2
' (gatefeed.bas) loads the FIFO when asked: VR(1) = the edge to load (1 bottom, 2 top),
' VR(2) = the edge loaded last, VR(3) = the last TABLE offset of an edge.

length = 50                  ' long edges [mm]
height = 20                  ' short edges [mm]
radius = 5                   ' corner radius [mm]
dash = 2                     ' dash and gap [mm]
speed = 50                   ' marking speed [mm/s]

VR(1) = 0
VR(2) = 0
WDOG = OFF
FOR ax = 2 TO 3
  BASE(ax)
  ATYPE = 35                 ' stepper output with PWM
  SERVO = ON                 ' the step pulses count as "encoder" pulses
  FE_LIMIT = 1
  UNITS = 80
  SPEED = speed
  ACCEL = 1000
  DECEL = 1000
NEXT ax
BASE(3, 2)                   ' X, Y interpolated: VP_SPEED of axis 3 is the path speed
DEFPOS(0, 0)
WAIT UNTIL OFFPOS = 0

' Dash positions: bottom edge (going +X) from TABLE(100), top edge (going -X) from TABLE(200).
n = 0
FOR x = 0 TO length - dash STEP 2 * dash
  TABLE(100 + n, x, x + dash)
  TABLE(200 + n, length - x, length - x - dash)
  n = n + 2
NEXT x
VR(3) = n - 2                ' leave out the last OFF: the final dash runs on into the corner

PWM_CONTROL(0)
PWM_CYCLE = 1000             ' 20 kHz
PWM_CONTROL(2, 1000000, 0, 600, 3)   ' mark = VP_SPEED * 10 clocks: 50 % at 50 mm/s
PWM_CONTROL(6)               ' PWM_ENCODER = 0 at X = 0
PWM_CONTROL(4)
PWM_CONTROL(5)               ' gating on: the laser follows the FIFO latch

IF IN(0) = OFF THEN
  PRINT "waiting for the lid to close"
  WAIT UNTIL IN(0) = ON
ENDIF
OP(8, ON)                    ' air assist
WDOG = ON
TICKS = 0
PRINT "engraving at "; speed; " mm/s"

edge = 1
GOSUB long_edge              ' bottom, +X
cx = 0 : cy = radius : ex = radius : ey = radius
GOSUB corner
MOVE(0, height)
cx = -radius : cy = 0 : ex = -radius : ey = radius
GOSUB corner
edge = 2
GOSUB long_edge              ' top, -X
cx = 0 : cy = -radius : ex = -radius : ey = -radius
GOSUB corner
MOVE(0, -height)
cx = radius : cy = 0 : ex = radius : ey = -radius
GOSUB corner
WAIT IDLE
PWM_CONTROL(4)               ' empty the FIFO: the gate closes
WDOG = OFF
OP(8, OFF)
PRINT "done in "; -TICKS; " ms, back at X "; DPOS; " Y "; DPOS AXIS(2)
GOTO finish

long_edge:
  VR(1) = edge               ' ask process 2 for this edge's dash positions
  WAIT UNTIL VR(2) = edge
  IF edge = 1 THEN
    MOVE(length, 0)
  ELSE
    MOVE(-length, 0)
  ENDIF
  RETURN

corner:
  MOVECIRC(ex, ey, cx, cy, 0)  ' a quarter circle, anticlockwise
  RETURN

finish:
