' heartbeat.bas - process 3: a background task that blinks output 15 every 100 ms for ever.
' It never ends by itself, so the machine file keeps it out of the job (job = false).
WHILE TRUE
  OP(15, ON)
  WA(100)
  OP(15, OFF)
  WA(100)
WEND
