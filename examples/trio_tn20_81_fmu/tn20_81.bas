WDOG=OFF
BASE(3) ' only axes 2 and 3 have this feature
PWM_CONTROL(0)
ATYPE=35 ' atype for stepper output with PWM
SERVO=ON ' required to allow stepper pulses to generate "encoder" pulses
FE_LIMIT=500000000 ' dpos and mpos may not match
PWM_CYCLE=1000 ' 20Khz PWM output
PWM_MARK=0 ' switch off for now
UNITS=16 '
PWM_CONTROL(1)
DEFPOS(0)
PWM_CONTROL(6)
TABLE(1000,110,115,195,220)
TABLE(2000,220,195,115,110)
PWM_CONTROL(4)
PWM_CONTROL(5) ' switch on gating function
PWM_MARK=400
WDOG=ON

REPEAT
  PWM_CONTROL(3,1,ON,1000,1003) ' load positions to gate
  MOVEABS(300)
  WAIT IDLE
  PWM_CONTROL(3,0,ON,2000,2003) ' same pattern in reverse
  MOVEABS(0)
  WAIT IDLE
UNTIL FALSE
