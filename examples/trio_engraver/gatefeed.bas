' gatefeed.bas - process 2 of the engraver: loads the dash positions of an edge into the gating
' FIFO of axis 3 when engrave.bas asks for them (VR(1) = edge), and says when they are in
' (VR(2) = edge). The FIFO holds 256 positions; an edge needs 25.

BASE(3)
fed = 0
WHILE fed < 2
  WAIT UNTIL VR(1) > fed
  fed = VR(1)
  IF fed = 1 THEN
    PWM_CONTROL(3, 1, ON, 100, 100 + VR(3))   ' GT going +X: ON at 0 mm, OFF at 2, ON at 4, ...
  ELSE
    PWM_CONTROL(3, 0, ON, 200, 200 + VR(3))   ' LT going -X: ON at 50 mm, OFF at 48, ...
  ENDIF
  PRINT "edge "; fed; ": "; VR(3) + 1; " positions in the FIFO"
  VR(2) = fed
WEND
