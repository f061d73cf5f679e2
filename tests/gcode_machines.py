"""Machine-file parts the G-code tests share."""

#: A router's x, y and z at 400 steps/mm: x and y up to 50 mm/s and 1000 mm/s^2, z up to 20 mm/s and 500 mm/s^2.
ROUTER_AXES = """\
[controller.axis.x]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
[controller.axis.y]
steps_per_unit = 400
max_velocity = 50
max_accel = 1000
[controller.axis.z]
steps_per_unit = 400
max_velocity = 20
max_accel = 500
"""
