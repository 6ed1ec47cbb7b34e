; A full circle in the YZ plane (G19, J/K centre offsets) and a line, about a work offset.
G21 G90 G19
G01 X0 Y0 Z-60
G02 Y0 Z-60 J0 K60
G01 Y40 Z-30
