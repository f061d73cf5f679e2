' main.bas - process 1 of the marking line (Trio EURO205X).
'
' Asks the operator for the batch size on the terminal (channel 0), starts the conveyor (axis 0) and
' registers each product as it passes the product sensor (REGIST on the conveyor: REG_POS is the
' conveyor position at the sensor's rising edge), handing the position to laser.bas through
' VR(regs + k). When the laser has marked the whole batch it stops the conveyor and prints a report.
INCLUDE "defs"
GLOBAL "batch", 10
GLOBAL "registered", 11
GLOBAL "marked", 12
DIM k AS INTEGER
DIM reg_mm(10), reg_ms(10) AS INTEGER
DIM answer AS STRING(20)

ON BASICERROR GOTO failed
registered = 0
marked = 0
TICKS = 0

' the conveyor: a stepper, 80 steps/mm, running continuously
BASE(0)
ATYPE = 1
UNITS = 80
SPEED = conveyor_speed
ACCEL = 1000
DECEL = 1000
FORWARD
REGIST(1)                        ' armed for the first product: the sensor's rising edge (input 1)

PRINT "batch size?"
INPUT #0, batch
IF batch < 1 OR batch > max_batch THEN
  PRINT "a batch is 1.."; max_batch[0]; " products, not "; batch
  STOP
ENDIF
answer = "batch of " + STR(batch)
PRINT answer

FOR k = 0 TO batch - 1
  WAIT UNTIL MARK
  reg_mm(k) = REG_POS
  reg_ms(k) = -TICKS
  IF k < batch - 1 THEN REGIST(1)
  VR(regs + k) = reg_mm(k)
  registered = k + 1
  PRINT "product "; (k + 1)[0]; " at"; reg_mm(k)[8, 2]; " mm"
NEXT k

WAIT UNTIL marked = batch
CANCEL
WAIT IDLE
FOR k = 0 TO batch - 1
  PRINT "report: product "; (k + 1)[0]; " registered at"; reg_mm(k)[8, 2]; " mm,"; reg_ms(k)[6, 0]; " ms"
NEXT k
PRINT "line stopped at "; -TICKS; " ms, conveyor at"; DPOS[8, 2]; " mm"
STOP

failed:
PRINT "line error "; RUN_ERROR; " at line "; ERROR_LINE; ": stopping every axis"
RAPIDSTOP
HALT
