' defs.bas - the marking line's constants, INCLUDEd by main.bas and laser.bas
CONSTANT "conveyor_speed", 100   ' mm/s
CONSTANT "laser_offset", 50      ' mm: the laser head sits 50 mm downstream of the product sensor
CONSTANT "mark_start", 5         ' mm of carriage travel where the mark starts (gate ON)
CONSTANT "mark_end", 35          ' mm where it ends (gate OFF)
CONSTANT "follow_length", 40     ' mm the carriage rides with a product
CONSTANT "lift_work", 3          ' mm: working height of the lift after homing
CONSTANT "regs", 200             ' VR(200..209): REG_POS of each product [mm]
CONSTANT "max_batch", 10
