' laser.bas - process 2 of the marking line: homes the laser lift, then marks each product as it
' passes under the laser.
'
' The lift (axis 2, a stepper on an 8 mm lead screw: 400 steps/mm) homes on its switch (input 6)
' with DATUM(4) and moves to its working height. The laser carriage (axis 3: stepper output with
' PWM, TN20-81) waits at 0. When the conveyor has carried a product laser_offset mm past the
' sensor, the carriage rides with it (CONNECT 1:1 to the conveyor's measured position) and the
' gating FIFO opens the laser at mark_start and closes it at mark_end mm of the carriage's travel,
' at the exact step. After follow_length mm the carriage lets go and returns to 0.
INCLUDE "defs"
GLOBAL "batch", 10
GLOBAL "registered", 11
GLOBAL "marked", 12
DIM done AS INTEGER
DIM target

BASE(2)
ATYPE = 1
UNITS = 400
SPEED = 20
ACCEL = 200
DECEL = 200
CREEP = 2
DATUM_IN = 6
P_GAIN = 0.5                     ' a stepper has no servo loop: stored, listed as not modelled
DATUM(4)                         ' down to the switch, creep up until it resets: DPOS = 0 there
WAIT IDLE
PRINT "lift homed at "; DPOS; " mm"
MOVEABS(lift_work)

BASE(3)
WDOG = OFF
PWM_CONTROL(0)
ATYPE = 35
SERVO = ON
FE_LIMIT = 2
UNITS = 80
SPEED = 200
ACCEL = 4000
DECEL = 4000
PWM_CYCLE = 1000                 ' 20 kHz
PWM_MARK = 500                   ' 50 %
PWM_CONTROL(1)
DEFPOS(0)
WAIT UNTIL OFFPOS = 0
PWM_CONTROL(6)                   ' PWM_ENCODER = 0 at carriage 0
PWM_CONTROL(4)
PWM_CONTROL(5)                   ' gating on: the FIFO latch gates the laser
TABLE(100, mark_start, mark_end)
WAIT IDLE AXIS(2)
WDOG = ON

WAIT UNTIL batch > 0
done = 0
WHILE done < batch
  WAIT UNTIL registered > done
  target = VR(regs + done) + laser_offset
  PWM_CONTROL(3, 1, ON, 100, 101)   ' GT going +: ON above mark_start, OFF above mark_end
  WAIT UNTIL MPOS AXIS(0) >= target
  CONNECT(1, 0)                  ' one carriage step per conveyor step
  WAIT UNTIL DPOS >= follow_length
  CANCEL
  WAIT IDLE
  MOVEABS(0)
  WAIT IDLE
  done = done + 1
  marked = done
  PRINT "marked product "; done[0]
WEND
WDOG = OFF
